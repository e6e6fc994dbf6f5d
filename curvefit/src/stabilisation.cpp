#include "ema/curvefit/stabilisation.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <sstream>

#include "ema/core/error.hpp"

namespace ema::curvefit {

const Eigen::VectorXcd& PoleVector(const Pole& pole) {
  return pole.participation.size() >= 2 ? pole.participation : pole.shape;
}

double Mac(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b) {
  if (a.size() == 0 || b.size() == 0 || a.size() != b.size()) return 1.0;
  const double den = a.squaredNorm() * b.squaredNorm();
  return den > 0.0 ? std::norm(a.dot(b)) / den : 0.0;
}

namespace {

double PoleDistance(const Pole& a, const Pole& b) {
  const double dl = std::abs(a.lambda - b.lambda) / std::max(std::abs(a.lambda), std::abs(b.lambda));
  return dl + (1.0 - Mac(PoleVector(a), PoleVector(b)));
}


double Quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const double pos = q * (v.size() - 1);
  const size_t i = static_cast<size_t>(pos);
  return i + 1 < v.size() ? v[i] + (pos - i) * (v[i + 1] - v[i]) : v.back();
}

double StdDev(const std::vector<double>& v) {
  if (v.size() < 2) return 0.0;
  const double mean = std::accumulate(v.begin(), v.end(), 0.0) / v.size();
  double ss = 0.0;
  for (double x : v) ss += (x - mean) * (x - mean);
  return std::sqrt(ss / (v.size() - 1));
}

/// Disjoint sets of 0..n−1 (union-find with path halving): the clusters the average linkage and
/// the fragment join build.
struct DisjointSets {
  explicit DisjointSets(int n) : parent(static_cast<size_t>(n)) { std::iota(parent.begin(), parent.end(), 0); }
  int Find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  std::vector<int> parent;
};

/// Average-linkage agglomerative clustering by the nearest-neighbour chain (O(k^2)); returns a
/// cluster id per item for the dendrogram cut at `cutoff`.
std::vector<int> AverageLinkage(const std::vector<const Pole*>& items, double cutoff) {
  const int k = static_cast<int>(items.size());
  DisjointSets sets(k);
  if (k > 1) {
    Eigen::MatrixXd d(k, k);
    for (int i = 0; i < k; ++i) {
      d(i, i) = 0.0;
      for (int j = i + 1; j < k; ++j) d(i, j) = d(j, i) = PoleDistance(*items[i], *items[j]);
    }
    std::vector<int> size(k, 1);
    std::vector<char> active(k, 1);
    std::vector<int> chain;
    int remaining = k;
    while (remaining > 1) {
      if (chain.empty())
        for (int i = 0; i < k; ++i)
          if (active[i]) {
            chain.push_back(i);
            break;
          }
      const int a = chain.back();
      const int prev = chain.size() >= 2 ? chain[chain.size() - 2] : -1;
      int best = prev;
      double best_d = prev >= 0 ? d(a, prev) : std::numeric_limits<double>::infinity();
      for (int c = 0; c < k; ++c)
        if (active[c] && c != a && d(a, c) < best_d) {
          best = c;
          best_d = d(a, c);
        }
      if (best != prev) {
        chain.push_back(best);
        continue;
      }
      chain.pop_back();
      chain.pop_back();
      // Merge prev into a (Lance-Williams update for average linkage).
      if (best_d <= cutoff) sets.parent[sets.Find(prev)] = sets.Find(a);
      for (int c = 0; c < k; ++c)
        if (active[c] && c != a && c != prev)
          d(a, c) = d(c, a) = (size[a] * d(a, c) + size[prev] * d(prev, c)) / (size[a] + size[prev]);
      size[a] += size[prev];
      active[prev] = 0;
      --remaining;
    }
  }
  std::vector<int> id(k);
  for (int i = 0; i < k; ++i) id[i] = sets.Find(i);
  return id;
}

/// Joins the clusters that are fragments of one column: a column whose pole vector or frequency
/// drifts along the orders by more than the cut-off (a mode that roving sets, loading the
/// structure with their sensors differently, see at slightly different frequencies: each order's
/// shape is a different blend of the sets' poles) is cut by the average linkage into pieces each
/// too short to count. A mode appears once per order, so clusters that never share an order and
/// whose median frequencies lie within `frequency_tol` are one column; pairs are joined nearest
/// first while the joined clusters still share no order. Two close modes are seen at the same
/// orders and stay apart.
void JoinColumnFragments(std::vector<std::vector<const Pole*>>* clusters, double frequency_tol) {
  if (!(frequency_tol > 0.0) || clusters->size() < 2) return;
  const int c = static_cast<int>(clusters->size());
  std::vector<double> median(c);
  int max_order = 0;
  for (int i = 0; i < c; ++i) {
    std::vector<double> f;
    for (const Pole* p : (*clusters)[i]) f.push_back(p->frequency_hz), max_order = std::max(max_order, p->order);
    median[i] = Quantile(f, 0.5);
  }
  std::vector<std::vector<char>> orders(c, std::vector<char>(static_cast<size_t>(max_order) + 1, 0));
  for (int i = 0; i < c; ++i)
    for (const Pole* p : (*clusters)[i]) orders[i][static_cast<size_t>(std::max(p->order, 0))] = 1;
  struct Pair {
    double d;
    int i, j;
  };
  std::vector<int> by_frequency(c);
  std::iota(by_frequency.begin(), by_frequency.end(), 0);
  std::sort(by_frequency.begin(), by_frequency.end(), [&](int a, int b) { return median[a] < median[b]; });
  std::vector<Pair> pairs;
  for (int a = 0; a < c; ++a)
    for (int b = a + 1; b < c; ++b) {
      const int i = by_frequency[a], j = by_frequency[b];
      const double d = (median[j] - median[i]) / std::max(median[j], 1e-300);
      if (!(d <= frequency_tol)) break;  // sorted: every later one is farther
      pairs.push_back({d, i, j});
    }
  std::stable_sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) { return x.d < y.d; });
  DisjointSets columns(c);
  for (const Pair& pr : pairs) {
    const int a = columns.Find(pr.i), b = columns.Find(pr.j);
    if (a == b) continue;
    bool shared = false;
    for (size_t o = 0; o < orders[a].size() && !shared; ++o) shared = orders[a][o] && orders[b][o];
    if (shared) continue;
    for (size_t o = 0; o < orders[a].size(); ++o) orders[a][o] |= orders[b][o];
    columns.parent[b] = a;
  }
  std::vector<std::vector<const Pole*>> joined;
  std::vector<int> slot(c, -1);
  for (int i = 0; i < c; ++i) {
    const int r = columns.Find(i);
    if (slot[r] < 0) slot[r] = static_cast<int>(joined.size()), joined.emplace_back();
    auto& to = joined[static_cast<size_t>(slot[r])];
    to.insert(to.end(), (*clusters)[i].begin(), (*clusters)[i].end());
  }
  *clusters = std::move(joined);
}

}  // namespace

void ClassifyStability(StabilisationDiagram* diagram, const StabilityOptions& options) {
  auto& orders = diagram->orders;
  for (auto& p : orders)
    for (auto& pole : p) {
      pole.label = 'o';
      pole.match_distance = std::numeric_limits<double>::quiet_NaN();
    }
  for (size_t k = 1; k < orders.size(); ++k) {
    auto& prev = orders[k - 1];
    auto& cur = orders[k];
    struct Pair {
      double d;
      int i, j;
    };
    std::vector<Pair> pairs;
    for (int i = 0; i < static_cast<int>(cur.size()); ++i) {
      if (!cur[i].physical) continue;
      for (int j = 0; j < static_cast<int>(prev.size()); ++j) {
        if (!prev[j].physical) continue;
        const double d = std::abs(cur[i].frequency_hz - prev[j].frequency_hz) / prev[j].frequency_hz;
        if (d < options.frequency_tol) pairs.push_back({d, i, j});
      }
    }
    std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.d < b.d; });
    std::vector<char> used_i(cur.size(), 0), used_j(prev.size(), 0);
    for (const Pair& pr : pairs) {
      if (used_i[pr.i] || used_j[pr.j]) continue;
      used_i[pr.i] = used_j[pr.j] = 1;
      Pole& a = cur[pr.i];
      const Pole& b = prev[pr.j];
      const bool damp = std::abs(a.damping_ratio - b.damping_ratio) < options.damping_tol * b.damping_ratio;
      const bool vec = Mac(PoleVector(a), PoleVector(b)) >= options.mac_min;
      a.label = damp && vec ? 's' : damp ? 'd' : vec ? 'v' : 'f';
      a.match_distance = PoleDistance(a, b);
    }
  }
}

std::vector<SelectedPole> SelectPolesAuto(const StabilisationDiagram& diagram, const AutoSelectOptions& options) {
  std::vector<const Pole*> cand;
  for (const auto& p : diagram.orders)
    for (const auto& pole : p)
      if (pole.label == 's') cand.push_back(&pole);
  if (cand.empty())
    for (const auto& p : diagram.orders)
      for (const auto& pole : p)
        if (pole.label == 'd') cand.push_back(&pole);
  if (cand.empty()) return {};

  double cutoff = options.cutoff;
  if (cutoff <= 0.0) {
    std::vector<double> dist;
    for (const Pole* p : cand)
      if (std::isfinite(p->match_distance)) dist.push_back(p->match_distance);
    const double mean = dist.empty() ? 0.0 : std::accumulate(dist.begin(), dist.end(), 0.0) / dist.size();
    cutoff = std::clamp(mean + 2.0 * StdDev(dist), 0.005, 0.05);
  }

  // Poles whose frequencies differ by more than the cut-off can never be joined (d >= relative
  // frequency difference), so cluster frequency-separated groups independently.
  std::sort(cand.begin(), cand.end(), [](const Pole* a, const Pole* b) { return a->frequency_hz < b->frequency_hz; });
  std::vector<std::vector<const Pole*>> clusters;
  size_t start = 0;
  for (size_t k = 1; k <= cand.size(); ++k) {
    if (k < cand.size() && (cand[k]->frequency_hz - cand[k - 1]->frequency_hz) / cand[k]->frequency_hz <= cutoff)
      continue;
    std::vector<const Pole*> group(cand.begin() + start, cand.begin() + k);
    const std::vector<int> id = AverageLinkage(group, cutoff);
    std::vector<int> seen;
    for (size_t i = 0; i < group.size(); ++i) {
      auto it = std::find(seen.begin(), seen.end(), id[i]);
      if (it == seen.end()) {
        seen.push_back(id[i]);
        clusters.emplace_back();
        clusters.back().push_back(group[i]);
      } else {
        clusters[clusters.size() - seen.size() + (it - seen.begin())].push_back(group[i]);
      }
    }
    start = k;
  }

  JoinColumnFragments(&clusters, options.fragment_frequency_tol);

  const int n_orders = static_cast<int>(diagram.orders.size());
  const int min_size = std::max(options.min_orders, static_cast<int>(std::ceil(options.min_span_fraction * n_orders)));
  std::vector<SelectedPole> selected;
  for (auto& members : clusters) {
    auto medoid_of = [](const std::vector<const Pole*>& v) {
      size_t best = 0;
      double best_sum = std::numeric_limits<double>::infinity();
      for (size_t i = 0; i < v.size(); ++i) {
        double s = 0.0;
        for (size_t j = 0; j < v.size(); ++j) s += PoleDistance(*v[i], *v[j]);
        if (s < best_sum) best_sum = s, best = i;
      }
      return v[best];
    };
    // One pole per order: the one nearest the medoid.
    const Pole* medoid = medoid_of(members);
    std::vector<const Pole*> per_order;
    for (const Pole* p : members) {
      auto it = std::find_if(per_order.begin(), per_order.end(), [&](const Pole* q) { return q->order == p->order; });
      if (it == per_order.end())
        per_order.push_back(p);
      else if (PoleDistance(*p, *medoid) < PoleDistance(**it, *medoid))
        *it = p;
    }
    if (static_cast<int>(per_order.size()) < min_size) continue;
    // Outliers in frequency or damping (1.5 IQR) do not define the representative or spread.
    std::vector<double> f, z;
    for (const Pole* p : per_order) f.push_back(p->frequency_hz), z.push_back(p->damping_ratio);
    const double fq1 = Quantile(f, 0.25), fq3 = Quantile(f, 0.75), zq1 = Quantile(z, 0.25), zq3 = Quantile(z, 0.75);
    std::vector<const Pole*> kept;
    for (const Pole* p : per_order)
      if (p->frequency_hz >= fq1 - 1.5 * (fq3 - fq1) && p->frequency_hz <= fq3 + 1.5 * (fq3 - fq1) &&
          p->damping_ratio >= zq1 - 1.5 * (zq3 - zq1) && p->damping_ratio <= zq3 + 1.5 * (zq3 - zq1))
        kept.push_back(p);
    if (kept.empty()) kept = per_order;
    f.clear(), z.clear();
    for (const Pole* p : kept) f.push_back(p->frequency_hz), z.push_back(p->damping_ratio);
    // Representative: the medoid of the upper half of the orders. The LS damping bias shrinks
    // as the order grows (algorithms.md §2.11), so the converged end of the column is preferred.
    std::vector<int> orders;
    for (const Pole* p : kept) orders.push_back(p->order);
    std::sort(orders.begin(), orders.end());
    const int median_order = orders[orders.size() / 2];
    std::vector<const Pole*> upper;
    for (const Pole* p : kept)
      if (p->order >= median_order) upper.push_back(p);
    SelectedPole s;
    s.pole = *medoid_of(upper);
    s.frequency_spread_hz = StdDev(f);
    s.damping_spread = StdDev(z);
    s.cluster_size = static_cast<int>(per_order.size());
    s.first_order = orders.front();
    s.last_order = orders.back();
    selected.push_back(std::move(s));
  }
  // One column that drifted in frequency and was cut in two: clusters within 1 % whose orders do
  // not overlap (one ends where the other begins). The one that reaches the higher orders — the
  // converged end of the column — stands for it.
  std::sort(selected.begin(), selected.end(),
            [](const SelectedPole& a, const SelectedPole& b) { return a.last_order > b.last_order; });
  {
    std::vector<SelectedPole> kept;
    for (auto& s : selected) {
      bool earlier_part = false;
      for (const auto& k : kept)
        earlier_part = earlier_part ||
                       (std::abs(s.pole.frequency_hz - k.pole.frequency_hz) < 0.01 * k.pole.frequency_hz &&
                        s.last_order < k.first_order + (k.last_order - k.first_order) / 5);
      if (!earlier_part) kept.push_back(std::move(s));
    }
    selected = std::move(kept);
  }
  // Two kept clusters of one mode (a column that drifted): same frequency within the cut-off and
  // the same vector; keep the larger. Close modes with different vectors are both kept.
  std::sort(selected.begin(), selected.end(),
            [](const SelectedPole& a, const SelectedPole& b) { return a.cluster_size > b.cluster_size; });
  std::vector<SelectedPole> out;
  for (auto& s : selected) {
    bool dup = false;
    for (const auto& o : out)
      dup = dup || (std::abs(s.pole.frequency_hz - o.pole.frequency_hz) / o.pole.frequency_hz < cutoff &&
                    Mac(PoleVector(s.pole), PoleVector(o.pole)) > 0.9);
    if (!dup) out.push_back(std::move(s));
  }
  std::sort(out.begin(), out.end(),
            [](const SelectedPole& a, const SelectedPole& b) { return a.pole.frequency_hz < b.pole.frequency_hz; });
  return out;
}

std::vector<SelectedPole> SelectPolesNear(const StabilisationDiagram& diagram, const std::vector<double>& frequencies_hz) {
  std::vector<SelectedPole> out;
  for (double target : frequencies_hz) {
    const Pole* best = nullptr;
    for (const char* labels : {"s", "d", "fv", "o"}) {
      for (const auto& p : diagram.orders)
        for (const auto& pole : p) {
          if (!pole.physical || !std::strchr(labels, pole.label)) continue;
          if (std::abs(pole.frequency_hz - target) > 0.1 * target) continue;
          const double d = std::abs(pole.frequency_hz - target);
          if (!best || d < std::abs(best->frequency_hz - target) ||
              (d == std::abs(best->frequency_hz - target) && pole.order > best->order))
            best = &pole;
        }
      if (best) break;
    }
    if (best) {
      // The nearest pole fixes the column; within it take the highest order (most converged).
      // The column is the poles of that label near it in frequency and damping: a zoom band's
      // high orders put noise poles of other damping within the same 0.5 % of frequency.
      const Pole* column_best = best;
      for (const auto& p : diagram.orders)
        for (const auto& pole : p)
          if (pole.physical && pole.label == best->label &&
              std::abs(pole.frequency_hz - best->frequency_hz) < 0.005 * best->frequency_hz &&
              std::abs(pole.damping_ratio - best->damping_ratio) < 0.25 * best->damping_ratio &&
              pole.order > column_best->order)
            column_best = &pole;
      best = column_best;
    }
    if (!best) {
      std::ostringstream msg;
      msg << "no physical pole within 10 % of " << target << " Hz";
      throw InputError("--select", msg.str());
    }
    SelectedPole s;
    s.pole = *best;
    s.frequency_spread_hz = kNaN;
    s.damping_spread = kNaN;
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace ema::curvefit
