#include "ema/correlation/dof_match.hpp"

#include <cmath>
#include <limits>

namespace ema::correlation {
namespace {

// Model DOF index by (node, |direction|) with the sign of the stored direction.
struct ModelDofIndex {
  std::map<std::pair<int, int>, std::pair<int, double>> by_axis;
  std::map<int, int> node_present;

  explicit ModelDofIndex(const ModeSet& model) {
    for (int k = 0; k < static_cast<int>(model.dofs.size()); ++k) {
      const Dof& d = model.dofs[k];
      const int axis = std::abs(d.direction);
      by_axis.emplace(std::make_pair(d.node, axis), std::make_pair(k, d.direction < 0 ? -1.0 : 1.0));
      node_present[d.node] = 1;
    }
  }
  bool HasNode(int node) const { return node_present.count(node) > 0; }
  // Index and sign of the model's value along +axis at node; {-1, 0} if absent.
  std::pair<int, double> Find(int node, int axis) const {
    auto it = by_axis.find({node, axis});
    return it == by_axis.end() ? std::make_pair(-1, 0.0) : it->second;
  }
};

}  // namespace

Eigen::MatrixXcd DofMatch::TestShapes(const ModeSet& test) const {
  Eigen::MatrixXcd shapes(shared.size(), test.modes.size());
  for (size_t m = 0; m < test.modes.size(); ++m)
    for (size_t i = 0; i < shared.size(); ++i) shapes(i, m) = test.modes[m].shape(shared[i].test_index);
  return shapes;
}

Eigen::MatrixXcd DofMatch::ModelShapes(const ModeSet& model) const {
  Eigen::MatrixXcd shapes = Eigen::MatrixXcd::Zero(shared.size(), model.modes.size());
  for (size_t m = 0; m < model.modes.size(); ++m)
    for (size_t i = 0; i < shared.size(); ++i)
      for (const auto& [k, w] : shared[i].model_terms) shapes(i, m) += w * model.modes[m].shape(k);
  return shapes;
}

DofMatch MatchDofs(const ModeSet& test, const ModeSet& model, const DofMatchOptions& options) {
  const ModelDofIndex index(model);
  std::map<int, Eigen::Vector3d> model_xyz;
  for (const Node& n : model.geometry) model_xyz[n.id] = n.position;
  std::map<int, Eigen::Vector3d> test_xyz;
  for (const Node& n : test.geometry) test_xyz[n.id] = n.position;

  DofMatch match;
  std::map<int, int> node_of;  // test node → model node (0 = none), resolved once per node
  auto resolve = [&](int node) {
    auto cached = node_of.find(node);
    if (cached != node_of.end()) return cached->second;
    int found = 0;
    if (auto it = options.node_map.find(node); it != options.node_map.end()) {
      found = it->second;
      ++match.nodes_by_map;
    } else if (index.HasNode(node)) {
      found = node;
      ++match.nodes_by_id;
    } else if (options.tolerance_m > 0.0 && test_xyz.count(node)) {
      double best = std::numeric_limits<double>::infinity();
      for (const auto& [id, xyz] : model_xyz) {
        if (!index.HasNode(id)) continue;
        const double distance = (xyz - test_xyz[node]).norm();
        if (distance < best) {
          best = distance;
          found = id;
        }
      }
      if (best <= options.tolerance_m) {
        ++match.nodes_by_distance;
      } else {
        found = 0;
      }
    }
    node_of[node] = found;
    return found;
  };

  for (int t = 0; t < static_cast<int>(test.dofs.size()); ++t) {
    const Dof& dof = test.dofs[t];
    const int model_node = resolve(dof.node);
    const int axis = std::abs(dof.direction);
    const double sign = dof.direction < 0 ? -1.0 : 1.0;
    SharedDof shared{t, dof, model_node, {}};
    if (model_node != 0 && axis >= 1 && axis <= 6) {
      auto frame = options.test_frames.find(dof.node);
      if (frame == options.test_frames.end() || axis > 3) {
        // Same axis: only a sign to reconcile (rotations are projected only for translations).
        const auto [k, model_sign] = index.Find(model_node, axis);
        if (k >= 0) shared.model_terms.push_back({k, sign * model_sign});
      } else {
        // The test axis is column (axis-1) of the node's frame, in global coordinates: it
        // measures the projection of the model's translation vector on that direction.
        const Eigen::Vector3d n = sign * frame->second.col(axis - 1);
        bool complete = true;
        for (int g = 0; g < 3; ++g) {
          if (std::abs(n(g)) < 1e-12) continue;
          const auto [k, model_sign] = index.Find(model_node, g + 1);
          if (k < 0) {
            complete = false;
            break;
          }
          shared.model_terms.push_back({k, n(g) * model_sign});
        }
        if (!complete) shared.model_terms.clear();
      }
    }
    if (shared.model_terms.empty()) {
      match.test_only.push_back(dof);
    } else {
      match.shared.push_back(std::move(shared));
    }
  }
  return match;
}

}  // namespace ema::correlation
