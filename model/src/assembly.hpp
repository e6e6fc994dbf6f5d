// What the reduced models of reduced.cpp need of the assembly in solve.cpp (not installed): the
// bodies', point masses' and springs' share of M and K of a changed model as triplets, without
// building the n × n matrices, the DOF names and the observation of a whole FE-sized system —
// the diagnosis asks for it once per reduced evaluation, thousands of times.
#pragma once

#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "ema/model/model.hpp"
#include "ema/model/solve.hpp"

namespace ema::model::detail {

class RestAssembler {
 public:
  /// The DOF layout (bodies, [fe] DOF map) and node positions of `layout`, kept for every model
  /// assembled later: effects change neither.
  explicit RestAssembler(const Model& layout);
  ~RestAssembler();
  RestAssembler(const RestAssembler&) = delete;
  RestAssembler& operator=(const RestAssembler&) = delete;

  /// True when `model` has the layout's bodies, in order (its [fe] DOF map and node positions are
  /// not read: the layout's stand for them, so a copy without them will do).
  bool Fits(const Model& model) const;
  /// The triplets Assemble(model, options) makes of bodies, point masses (the options' extra
  /// masses too) and springs, in its order; throws InputError as Assemble does.
  void Assemble(const Model& model, const SolveOptions& options, std::vector<Eigen::Triplet<double>>* mass,
                std::vector<Eigen::Triplet<double>>* stiffness) const;

 private:
  struct Layout;
  std::unique_ptr<Layout> layout_;
};

}  // namespace ema::model::detail
