// Rotor inertia and friction of the layout's slots: the one place that says where they act.
//
// Slot k acts on joint k (t_k = e_k), or, when the model's `motorSide()`, on motor k through row
// t_k of the transmission T (model.hpp): with the slot velocity v_k = t_k . dq and acceleration
// a_k = t_k . ddq its joint torques are
//   t_k^T (Ia_k a_k + sum_j F_kj phi_j(v_k)),
// phi the friction features of the slot (frictionShapes of the model's friction model), its kinetic
// energy 1/2 Ia_k v_k^2, its share of the mass matrix Ia_k t_k t_k^T and of the momentum
// Ia_k t_k v_k. Every function here allocates nothing and throws nothing; `checkDriveSide` (at
// setup) makes sure T has one row per slot when they are used.
#pragma once

#include "mindyn/dynamics.hpp"
#include "mindyn/spatial.hpp"

namespace mindyn::drive {

/// Velocity (or acceleration, given ddq) of slot k: t_k . dq on the motor side, dq_k otherwise.
inline double motorVelocity(const Model& model, int k, const VecRef& dq) noexcept {
  if (!model.motorSide()) return dq[k];
  return model.transmission.T.row(k).dot(dq);
}

/// The friction features of slot k at slot velocity v, one per friction column of the layout:
/// the slot's friction torque is sum_j params[viscousIndex(k) + j] * out[j].
inline void frictionFeatures(const Model& model, ParameterLayout /*layout*/, int k, double v,
                             double* out) noexcept {
  out[2] = 0.0;  // the friction models without a third column leave it
  slotFrictionShapes(model, k, v, out);
}

/// Adds to `tau` the joint torques of every slot's rotor inertia (at `ddq`) and friction (at
/// `dq`).
inline void addDriveTorques(const Model& model, ParameterLayout layout, const VecRef& params,
                            const VecRef& dq, const VecRef& ddq, VecOut tau) noexcept {
  if (!layout.rotor && !layout.friction) return;
  const int n = static_cast<int>(tau.size());
  const bool motors = model.motorSide();
  for (int k = 0; k < n; ++k) {
    double t = 0.0;
    if (layout.rotor) t = params[layout.rotorIndex(k)] * motorVelocity(model, k, ddq);
    if (layout.friction) {
      double phi[3];
      frictionFeatures(model, layout, k, motorVelocity(model, k, dq), phi);
      const int c = layout.viscousIndex(k);
      double f = params[c] * phi[0];
      for (int j = 1; j < layout.friction_columns; ++j) f += params[c + j] * phi[j];
      if (!motors) {  // as before transmissions: Ia ddq, then the friction, added to tau_k
        if (layout.rotor) tau[k] += t;
        tau[k] += f;
        continue;
      }
      t += f;
    } else if (!motors) {
      tau[k] += t;
      continue;
    }
    tau += t * model.transmission.T.row(k).transpose();
  }
}

/// Adds each joint's torque offset (the layout's joint block) to `tau`: a joint torque on either
/// drive side.
inline void addOffsets(ParameterLayout layout, const VecRef& params, VecOut tau) noexcept {
  if (!layout.offset) return;
  const int n = static_cast<int>(tau.size());
  tau += params.segment(layout.offsetIndex(n, 0), n);
}

/// Writes the offset columns of a regressor W (n x layout.size(n)): e_k, the torque a unit
/// offset of joint k gives (the inverse-dynamics regressor and -dL/dq + offsets of the momentum
/// regressors).
inline void offsetColumns(ParameterLayout layout, MatOut W) noexcept {
  if (!layout.offset) return;
  const int n = static_cast<int>(W.rows());
  W.middleCols(layout.offsetIndex(n, 0), n).setIdentity();
}

/// Writes the rotor columns of a regressor W (n x layout.size(n), the other entries of those
/// columns zero) at slot accelerations from `ddq` (the momentum's at velocities: pass dq).
inline void rotorColumns(const Model& model, ParameterLayout layout, const VecRef& ddq,
                         MatOut W) noexcept {
  if (!layout.rotor) return;
  const bool motors = model.motorSide();
  for (int k = 0; k < static_cast<int>(W.rows()); ++k) {
    const double a = motorVelocity(model, k, ddq);
    if (motors)
      W.col(layout.rotorIndex(k)) = a * model.transmission.T.row(k).transpose();
    else
      W(k, layout.rotorIndex(k)) = a;
  }
}

/// Writes the friction columns of a regressor W (as rotorColumns) at `dq`.
inline void frictionColumns(const Model& model, ParameterLayout layout, const VecRef& dq,
                            MatOut W) noexcept {
  if (!layout.friction) return;
  const bool motors = model.motorSide();
  for (int k = 0; k < static_cast<int>(W.rows()); ++k) {
    double phi[3];
    frictionFeatures(model, layout, k, motorVelocity(model, k, dq), phi);
    for (int j = 0; j < layout.friction_columns; ++j) {
      const int c = layout.viscousIndex(k) + j;
      if (motors)
        W.col(c) = phi[j] * model.transmission.T.row(k).transpose();
      else
        W(k, c) = phi[j];
    }
  }
}

/// Both: the rotor columns at `ddq`, the friction columns at `dq`.
inline void driveColumns(const Model& model, ParameterLayout layout, const VecRef& dq,
                         const VecRef& ddq, MatOut W) noexcept {
  rotorColumns(model, layout, ddq, W);
  frictionColumns(model, layout, dq, W);
}

}  // namespace mindyn::drive
