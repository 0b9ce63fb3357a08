// Inverse dynamics in the base parameters at run time: tau(q, dq, ddq; p_b), the gravity torque
// and the base regressor W_b, by the Newton-Euler recursion customised to the model.
//
// At setup the recursion is written into an expression graph (codegen/newton_euler.hpp) with
// the model's exact geometric zeros and ones and with p_b at the pivot positions of the
// classical vector (every non-base entry exactly zero), folded, de-duplicated and pruned; what
// remains is flattened into a tape of instructions of a few kinds: a * b, a + b, a - b, and a
// product feeding a single sum fused into it (a * b + c, a * b - c, c - a * b); the sine and
// cosine of one angle together (mindyn/sincos.hpp); sign. Instructions are ordered into runs of
// one kind, each evaluated by its own loop, so that the evaluation branches per run, not per
// operation. The per-call functions allocate nothing and throw nothing; sizes are
// preconditions (the Python binding checks them). One object per thread: the workspace is
// inside.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "mindyn/base_parameters.hpp"
#include "mindyn/codegen/newton_euler.hpp"
#include "mindyn/dynamics.hpp"

namespace mindyn {

/// A straight-line program compiled from a generated function for repeated evaluation.
class Tape {
 public:
  Tape() = default;
  explicit Tape(const codegen::GeneratedFunction& f);

  /// Evaluates; `out` receives the function's outputs (n, or n * np row-major).
  void run(const double* q, const double* dq, const double* ddq, const double* p,
           double* out) noexcept;

  /// Operation counts of the generated function (before fusing).
  const codegen::OpCount& count() const { return count_; }
  /// Tape instructions (fused; one per sine-cosine pair) and runs of one kind.
  int instructions() const { return static_cast<int>(code_.size()); }
  int runs() const { return static_cast<int>(runs_.size()); }

 private:
  // Mul: a * b; Add, Sub: a + c, a - c; MulAdd, MulSub: a * b + c, a * b - c; SubMul:
  // c - a * b; SinCos: sin a to slot b, cos a to slot c; Sign: sign(a); Tanh: tanh(a); Exp:
  // exp(a), of -a when b is 1.
  enum Kind : std::uint8_t { Mul, Add, Sub, MulAdd, MulSub, SubMul, SinCos, Sign, Tanh, Exp };
  static constexpr int kKinds = 10;
  struct Run {
    Kind kind;
    std::uint32_t begin, end;  // range in code_; results go to slots first_ + begin ...
  };
  struct Instruction {
    std::uint32_t a, b, c;  // slots
  };
  struct Load {
    std::uint32_t slot;
    codegen::InputKind kind;
    std::uint32_t index;
  };
  std::vector<double> slots_;
  std::vector<Load> loads_;
  std::vector<Run> runs_;
  std::vector<Instruction> code_;
  std::vector<std::pair<std::uint32_t, bool>> outputs_;  // slot, negated
  std::uint32_t first_ = 0;                              // slot of the first computed value
  codegen::OpCount count_;
};

class BaseDynamics {
 public:
  /// Throws ModelError when `base` does not belong to `model`.
  BaseDynamics(const Model& model, const BaseParameters& base);
  /// The same from a parameter set (codegen::baseParameterSet, or any pi = E p map).
  BaseDynamics(const Model& model, const codegen::ParameterSet& params);

  int nq() const { return n_; }
  /// Number of base parameters (equations-of-motion set, friction and rotor when enabled).
  int np() const { return np_; }
  const std::vector<std::string>& names() const { return names_; }
  ParameterLayout layout() const { return layout_; }

  /// tau = W_b(q, dq, ddq) p_b, friction and rotor inertia included when in the layout.
  void inverseDynamics(const VecRef& q, const VecRef& dq, const VecRef& ddq, const VecRef& pb,
                       VecOut tau) noexcept;
  /// Gravity torque c(q) for p_b.
  void gravity(const VecRef& q, const VecRef& pb, VecOut tau) noexcept;
  /// W_b (n x np).
  void regressor(const VecRef& q, const VecRef& dq, const VecRef& ddq, MatOut Wb) noexcept;

  /// Operation counts of the three tapes.
  const codegen::OpCount& count(codegen::Function f) const;
  /// Geometric constants taken as exactly 0 or +-1 (codegen::kGeometrySnap), over the tapes.
  const codegen::GeometrySnap& geometrySnap() const { return snap_; }

 private:
  int n_ = 0, np_ = 0;
  ParameterLayout layout_;
  std::vector<std::string> names_;
  Tape id_, gravity_, regressor_;
  codegen::GeometrySnap snap_;
  Eigen::VectorXd qb_, dqb_, ddqb_, pb_, out_;
};

}  // namespace mindyn
