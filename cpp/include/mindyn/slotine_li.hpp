// The Slotine-Li regressor: the equations of motion with the velocity that multiplies the
// Coriolis matrix and the acceleration replaced by a reference velocity and acceleration,
//
//   Y(q, dq, dqr, ddqr) p = A(q) ddqr + C(q, dq) dqr + c(q)  (+ Fv dq + Fc sign(dq)),
//
// with C the Coriolis matrix of the Christoffel symbols of A (so dA/dt - 2 C is skew-symmetric,
// and C, like A and c, depends on the parameters only through the base parameters). Used by
// adaptive controllers (tau = Y p_hat - K_D s, dp_hat/dt = -Gamma Y^T s).
//
// Computed as a modified Newton-Euler recursion that carries the actual link velocity v and the
// reference velocity v_r = J dqr and acceleration a_r = J ddqr + dJ/dt dqr + v x v_r:
//
//   f = I (a_r - 1/2 v x v_r) + 1/2 (v x* (I v_r) + v_r x* (I v)),
//
// which for dqr = dq, ddqr = ddq is the ordinary Newton-Euler force I a + v x* I v. Conventions as
// in dynamics.hpp. Every function here allocates nothing and throws nothing.
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

/// Workspace of the Slotine-Li functions, built once per model and layout (allocates).
struct SlotineLiData {
  SlotineLiData(const Model& model, ParameterLayout layout = {});

  int n;
  ParameterLayout layout;
  std::vector<Vector6d> vr, ar;  // reference velocity and acceleration of each link
  Matrix6x10 F;
  Eigen::MatrixXd W;            // n x layout.size(n): classical regressor for the base one
  Eigen::VectorXd zeros, unit;  // n
};

/// Classical Slotine-Li regressor Y (n x layout.size(n)); `layout` must be the workspace's.
void slotineLiRegressor(const Model& model, Data& data, SlotineLiData& sl, const VecRef& q,
                        const VecRef& dq, const VecRef& dqr, const VecRef& ddqr,
                        ParameterLayout layout, MatOut Y) noexcept;

/// Base Slotine-Li regressor Y_b = Y(:, pivots) of the equations-of-motion set (n x base.eom.size):
/// Y_b p_b = A ddqr + C dqr + c (+ friction). `sl` must be built with base.layout.
void slotineLiBaseRegressor(const Model& model, Data& data, SlotineLiData& sl,
                            const BaseParameters& base, const VecRef& q, const VecRef& dq,
                            const VecRef& dqr, const VecRef& ddqr, MatOut Yb) noexcept;

/// tau = Y(q, dq, dqr, ddqr) params for a classical parameter vector, without forming Y. With
/// `with_gravity` false the gravity torque c(q) is left out; with `joint_terms` false so are the
/// rotor and friction terms.
void slotineLiTorque(const Model& model, Data& data, SlotineLiData& sl, const VecRef& q,
                     const VecRef& dq, const VecRef& dqr, const VecRef& ddqr, const VecRef& params,
                     ParameterLayout layout, VecOut tau, bool with_gravity = true,
                     bool joint_terms = true) noexcept;

/// The Coriolis matrix C(q, dq) (n x n) of the same factorisation for a classical parameter
/// vector: b(q, dq) = C(q, dq) dq, dA/dt - 2 C skew-symmetric.
void coriolisMatrix(const Model& model, Data& data, SlotineLiData& sl, const VecRef& q,
                    const VecRef& dq, const VecRef& params, ParameterLayout layout,
                    MatOut C) noexcept;

}  // namespace mindyn
