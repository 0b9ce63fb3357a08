// Fixed-step integration of the forward dynamics with the joint torque held: the plant of the
// closed-loop simulations. A discrete-time controller computes a torque once per period; the
// robot then moves under that torque for the period,
//
//   A(q) ddq + b(q, dq) + c(q) + Fv dq + f(dq) = tau,
//
// f the friction shapes of the model's friction model (model.hpp) with sign(dq) replaced by
// tanh(dq / eps) when eps > 0 (on the motor side, Model::motorSide, rotor inertia and friction
// act through the transmission: A includes T^T Ia T, and the friction is T^T f(T dq)),
// integrated by `substeps` classical Runge-Kutta (RK4) steps of h = period / substeps (global
// error O(h^4)). The friction terms other than the viscous one are taken out of the parameter
// vector and applied as a torque, so that the sign in them can be smoothed (eps > 0) where a
// switching sign would make the right-hand side discontinuous.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Core>

#include "mindyn/data.hpp"
#include "mindyn/dynamics.hpp"
#include "mindyn/model.hpp"

namespace mindyn {

class Integrator {
 public:
  /// `params` in `layout` (the simulated robot's true parameters); `coulomb_smoothing` eps >= 0
  /// [rad/s | m/s] (0: Fc sign(dq)). Throws std::invalid_argument on a wrong size, a non-finite
  /// parameter or a negative or non-finite eps. Allocates (once); `model` must outlive this.
  Integrator(const Model& model, const Eigen::VectorXd& params, ParameterLayout layout,
             double coulomb_smoothing = 0.0);

  /// ddq = A(q)^-1 (tau - b - c - friction). False (ddq unchanged) when A(q) is not positive
  /// definite. Allocation-free.
  bool acceleration(Data& data, const VecRef& q, const VecRef& dq, const VecRef& tau,
                    VecOut ddq) noexcept;

  /// Advances (q, dq) by `dt` seconds in `substeps` RK4 steps with `tau` held. False when
  /// dt <= 0 or substeps < 1, when A(q) is not positive definite on the way or when the state
  /// becomes non-finite (q, dq are then partly advanced and must not be used). Allocation-free.
  bool step(Data& data, VecOut q, VecOut dq, const VecRef& tau, double dt, int substeps) noexcept;

  int n() const { return n_; }

 private:
  const Model& model_;
  int n_;
  ParameterLayout layout_;
  Eigen::VectorXd params_;    // friction entries but the viscous ones zeroed
  Eigen::MatrixXd friction_;  // n x 3: those entries (column 0 unused; zero without friction)
  double eps_;
  Eigen::VectorXd tau_, k1_, k2_, k3_, k4_, qs_, vs_, v2_, v3_;  // workspace
};

}  // namespace mindyn
