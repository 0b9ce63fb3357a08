// Generalised-momentum observer (De Luca's residual) of external joint torques, on the base
// parameters of an identified (or nominal) model, without accelerations:
//
//   r(t) = K_O (p(t) - p(0) - int_0^t (tau - beta + r) ds),   p = A(q) dq = W_p,b(q, dq) p_b,
//   beta = -dL/dq + tau_f + offset = W_l,b(q, dq) p_b + friction + offset,
//
// (-dL/dq = g - C^T dq, so tau - beta is De Luca's tau + C^T dq - g - tau_f). With the model
// exact, dr/dt = K_O (tau_ext - r): r is tau_ext through K_O / (s + K_O), per joint.
//
// Discretisation at the controller period T (samples k = 0, 1, ...): the integral advances by
//   T tau_{k-1}                      (held torque: the command held over the period, exact for it)
//   or T/2 (tau_k + tau_{k-1})        (sampled torque: a measured torque, trapezoid),
//   - T/2 (beta_k + beta_{k-1}) - T/2 (r_k + r_{k-1})   (trapezoid),
// and r_k is solved from its own implicit term: r_k = K_O / (1 + K_O T/2) (p_k - p_0 - S_k),
// S_k the integral without T/2 r_k. Equivalently r_k = a r_{k-1} + c D_k with a = (1 - K_O
// T/2) / (1 + K_O T/2), c = K_O / (1 + K_O T/2) and D_k = p_k - p_{k-1} - (the torque and
// beta increments): the discrete residual is exactly the bilinear (Tustin) image of K_O / (s +
// K_O) driven by the external-torque impulse D_k of each period (T tau_ext for a held one), up
// to the trapezoid's error on beta (O(T^3) per period). It is stable for every K_O > 0 and free
// of sign alternation for K_O T < 2 (a > 0), the range accepted.
//
// Friction and rotor terms come from the momentum regressors and the Newton-Euler regressor of
// the layout (their friction columns), so the observer follows their model.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "mindyn/base_parameters.hpp"
#include "mindyn/data.hpp"
#include "mindyn/dynamics.hpp"
#include "mindyn/model.hpp"

namespace mindyn {

class MomentumObserver {
 public:
  /// `values`: p_b of `base` (base.eom.size()); `gains`: K_O per joint [1/s], each in
  /// (0, 2 / period); `offset`: a constant torque per joint besides those of the base set's
  /// layout (its offsets are base parameters, in `values`; empty: none); `held_torque`: the
  /// torque is the command held over each period (else sampled, integrated by the trapezoid).
  /// Throws ModelError on a wrong size, a non-finite value or a gain out of range.
  /// Allocates (once); `model` and `base` must outlive it.
  MomentumObserver(const Model& model, const BaseParameters& base, const Eigen::VectorXd& values,
                   const Eigen::VectorXd& gains, double period,
                   const Eigen::VectorXd& offset = Eigen::VectorXd(), bool held_torque = true);

  /// The default gain of every joint for `period`: a time constant of ten periods,
  /// K_O = 1 / (10 T) [1/s] (K_O T = 0.1, a = 0.905; a bandwidth of 1/31 of the Nyquist
  /// frequency). The error of the trapezoid where Coulomb friction switches sign at a velocity
  /// reversal enters r as about K_O T Fc / 2: the lower K_O T, the smaller these spikes against
  /// the thresholds, at a delay of -10 T ln(1 - threshold / step) for a step.
  static double defaultGain(double period);

  /// Starts at sample 0: p(0) from (q, dq), the integral and r zero, tau the torque of sample 0.
  void reset(const VecRef& q, const VecRef& dq, const VecRef& tau) noexcept;
  /// Sample k >= 1: (q, dq, tau) of that sample; writes r_k. Allocation-free, throws nothing.
  void step(const VecRef& q, const VecRef& dq, const VecRef& tau, VecOut r) noexcept;
  /// The same `dt` seconds after the previous sample (a log with uneven time stamps; the
  /// caller keeps K_O dt < 2).
  void step(const VecRef& q, const VecRef& dq, const VecRef& tau, double dt, VecOut r) noexcept;

  /// p = W_p,b p_b and beta of a state (after reset/step: of the last sample).
  const Eigen::VectorXd& momentum() const { return p_; }
  const Eigen::VectorXd& beta() const { return beta_; }
  const Eigen::VectorXd& residual() const { return r_; }
  const Eigen::VectorXd& integral() const { return s_; }
  const Eigen::VectorXd& gains() const { return k_; }
  double period() const { return period_; }
  int n() const { return n_; }

 private:
  void evaluate(const VecRef& q, const VecRef& dq) noexcept;  // p_, beta_

  const Model& model_;
  const BaseParameters& base_;
  int n_;
  double period_;
  bool held_;
  Eigen::VectorXd values_, k_, c_, offset_;
  std::vector<long> friction_;  // base columns that are friction columns
  Data data_;
  Eigen::MatrixXd W_, Wp_, Wl_, Wpb_, Wlb_;
  Eigen::VectorXd p_, beta_, p0_, s_, r_, tau_prev_, beta_prev_;
};

}  // namespace mindyn
