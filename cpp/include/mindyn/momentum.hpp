// Regressors of the integral (momentum) form of the equations of motion:
//
//   tau_j = d/dt p_j - dL/dq_j (+ friction),   L = K - P,   p = A(q) dq,
//
// integrated over a window [t_a, t_b] this needs no acceleration:
//
//   int tau_j dt = p_j(t_b) - p_j(t_a) + int (-dL/dq_j) dt (+ int friction dt).
//
// Both p and -dL/dq are linear in the classical parameters: p = Wp(q, dq) pi and
// -dL/dq = Wl(q, dq) pi, in the layouts of model.hpp.
//
// Math (world-frame Plucker vectors, (angular; linear)): S_j the screw axis of joint j, v_i the
// twist of link i, I_i its spatial inertia and h_i = I_i v_i its spatial momentum. For k after
// j in the chain, dS_k/dq_j = S_j x S_k (motion cross product), hence dv_i/dq_j = S_j x (v_i -
// v_j) for i >= j; the world-frame inertia also turns, dI_i/dq_j = (S_j x*) I_i - I_i (S_j x).
// The two contributions to dK/dq_j = sum_i [dv_i/dq_j . h_i + 1/2 v_i . (dI_i/dq_j) v_i] add
// up to
//   dK/dq_j = (v_j x S_j) . sum_{i >= j} h_i,      p_j = S_j . sum_{i >= j} h_i  (+ rotor),
// (v_j x S_j = v_{j-1} x S_j as S_j x S_j = 0). dP/dq_j is the gravity torque. The rotor
// energy 1/2 Ia_k v_k^2 does not depend on q (v_k = dq_k, or t_k . dq on the motor side: its
// momentum Ia_k t_k v_k).
//
// Frames: as in dynamics.hpp, every spatial quantity is in link coordinates about the link
// origin; the sums over i >= j are carried from link to link towards the base like the wrench
// blocks of the Newton-Euler regressor, with the link momentum block (6 x 10, h_k = B_k
// pi_k: angular momentum I w + m c x v, linear momentum m v + w x m c) in place of the wrench
// block. Friction columns are zero in both; the rotor column of Wp is dq_k e_k
// (t_k v_k on the motor side), of Wl zero.
//
// Every function here allocates nothing and throws nothing after setup (Data built); sizes are
// preconditions (checked by the Python binding).
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include "mindyn/base_parameters.hpp"
#include "mindyn/data.hpp"
#include "mindyn/dynamics.hpp"
#include "mindyn/model.hpp"

namespace mindyn {

/// Wp (n x layout.size(n)): p = A(q) dq = Wp pi. Wl (n x layout.size(n)): -dL/dq = Wl pi =
/// -dK/dq + c(q), c the gravity torque; with torque offsets in the layout, Wl pi is
/// -dL/dq + offsets (their columns e_k, zero in Wp).
void momentumRegressors(const Model& model, Data& data, const VecRef& q, const VecRef& dq,
                        ParameterLayout layout, MatOut Wp, MatOut Wl) noexcept;

/// The same in the base parameters of the equations-of-motion set: Wpb = Wp(:, pivots),
/// Wlb = Wl(:, pivots). `Wp`, `Wl` are n x base.layout.size(n) work matrices.
void baseMomentumRegressors(const Model& model, Data& data, const BaseParameters& base,
                            const VecRef& q, const VecRef& dq, MatOut Wp, MatOut Wl, MatOut Wpb,
                            MatOut Wlb) noexcept;

}  // namespace mindyn
