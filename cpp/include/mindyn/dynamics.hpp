// Rigid-body dynamics of a fixed-base serial chain or tree, linear in the classical parameters.
//
// Conventions: link frames as in model.hpp; spatial vectors (angular; linear) about the link
// origin in link coordinates; gravity = model.gravity in the base frame. `params` is any vector
// in the given ParameterLayout, physically meaningful or not (regrouped base-parameter vectors
// are fed here too). Every function here allocates nothing and throws nothing; sizes are
// preconditions, which a caller checks once at setup with `checkSizes` (the Python binding checks
// its arguments itself, with messages in the terms of its own arguments).
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "mindyn/data.hpp"
#include "mindyn/model.hpp"
#include "mindyn/spatial.hpp"

namespace mindyn {

using VecRef = Eigen::Ref<const Eigen::VectorXd>;
using VecOut = Eigen::Ref<Eigen::VectorXd>;
using MatOut = Eigen::Ref<Eigen::MatrixXd>;

/// The friction columns of slot k at its velocity v (the one place they are formed): phi[i]
/// multiplies friction parameter i (layout.frictionIndex(k, i)) in the slot's torque, i below
/// f.columns() (model.hpp, FrictionModel): Coulomb {v, s}, Asymmetric {v, s, |s|}, Smooth
/// {v, tanh(v / w_k)}, Stribeck {v, s, s exp(-(v / w_k)^2)}, with s = sign(v) (sign(0) = 0), or
/// s = tanh(v / eps) when `sign_smoothing` eps > 0 (the simulation plant's smoothing). The
/// friction model must be valid for the model's slots (FrictionModel::validate).
inline void frictionShapes(const FrictionModel& f, int k, double v, double* phi,
                           double sign_smoothing = 0.0) noexcept {
  const double s = sign_smoothing > 0.0 ? std::tanh(v / sign_smoothing) : sgn(v);
  phi[0] = v;
  switch (f.kind) {
    case FrictionKind::Coulomb:
      phi[1] = s;
      break;
    case FrictionKind::Asymmetric:
      phi[1] = s;
      phi[2] = std::abs(s);
      break;
    case FrictionKind::Smooth:
      phi[1] = std::tanh(v / f.velocity[k]);
      break;
    case FrictionKind::Stribeck: {
      const double r = v / f.velocity[k];
      phi[1] = s;
      phi[2] = s * std::exp(-r * r);
      break;
    }
  }
}

/// The friction columns of slot k of `model` at the slot's velocity v: frictionShapes of its
/// friction model (every slot, joint or motor, has each of the model's terms). What every
/// regressor, simulation and the bindings take.
inline void slotFrictionShapes(const Model& model, int k, double v, double* phi,
                               double sign_smoothing = 0.0) noexcept {
  frictionShapes(model.friction_model, k, v, phi, sign_smoothing);
}

/// Slot k's friction torque sum_i params[layout.frictionIndex(k, i)] phi_i(v)
/// (slotFrictionShapes); zero without friction in the layout.
inline double frictionTorque(const Model& model, ParameterLayout layout, const VecRef& params,
                             int k, double v) noexcept {
  if (!layout.friction) return 0.0;
  double phi[3] = {0.0, 0.0, 0.0};
  slotFrictionShapes(model, k, v, phi);
  double t = 0.0;
  for (int i = 0; i < layout.friction_columns; ++i)
    t += params[layout.frictionIndex(k, i)] * phi[i];
  return t;
}

/// The kinematic pass of every algorithm here, of the Slotine-Li functions and of the inverse
/// kinematics: the pose of every link relative to its parent (data.R, p) and to the base
/// (data.R0, p0).
void forwardKinematics(const Model& model, Data& data, const VecRef& q) noexcept;

/// forwardKinematics, then the velocity and acceleration of every link (data.v, a). With
/// `with_gravity`, the base acceleration is -gravity so that inertial forces include weight.
void computeKinematics(const Model& model, Data& data, const VecRef& q, const VecRef& dq,
                       const VecRef& ddq, bool with_gravity = true) noexcept;

/// Newton-Euler inverse dynamics: tau = W(q, dq, ddq) * params. Rotor inertia and friction act
/// on the joints, or through the transmission when Model::motorSide (model.hpp); torque offsets
/// on the joints.
void inverseDynamics(const Model& model, Data& data, const VecRef& q, const VecRef& dq,
                     const VecRef& ddq, const VecRef& params, ParameterLayout layout,
                     VecOut tau) noexcept;

/// Throws std::invalid_argument unless a layout with friction has the friction model's columns
/// and the friction model is valid for the model (checkSizes calls it).
void checkFrictionLayout(const Model& model, ParameterLayout layout);

/// Gravity torque c(q) (friction, rotor inertia and torque offsets do not contribute).
void gravityTorque(const Model& model, Data& data, const VecRef& q, const VecRef& params,
                   ParameterLayout layout, VecOut tau) noexcept;

/// Classical regressor W (n x layout.size(n)) with tau = W * params. On a tree, the block of link
/// k is zero on the rows of joints that do not support it; the offset column of joint k is e_k.
void regressor(const Model& model, Data& data, const VecRef& q, const VecRef& dq, const VecRef& ddq,
               ParameterLayout layout, MatOut W) noexcept;

/// Kinetic and potential energy regressors (rows of length layout.size(n)):
/// K = wK * params, P = wP * params, total energy H = (wK + wP) * params, Lagrangian (wK - wP).
/// Friction columns are zero; the rotor column of slot k is 0.5 v_k^2 (v_k = dq_k, or the motor
/// velocity t_k . dq on the motor side, see Model::motorSide). The offset column of joint k in
/// wP is q_k, the offset's work (it is not an energy: kineticEnergy and potentialEnergy leave
/// offsets out), so that wP differences over a window give the energy model's offset columns.
void energyRegressors(const Model& model, Data& data, const VecRef& q, const VecRef& dq,
                      ParameterLayout layout, VecOut wK, VecOut wP) noexcept;

double kineticEnergy(const Model& model, Data& data, const VecRef& q, const VecRef& dq,
                     const VecRef& params, ParameterLayout layout) noexcept;
double potentialEnergy(const Model& model, Data& data, const VecRef& q, const VecRef& params,
                       ParameterLayout layout) noexcept;

/// Joint-space inertia matrix A(q) (with rotor inertia when in the layout: Ia_k on the diagonal,
/// or Ia_k t_k t_k^T on the motor side).
void massMatrix(const Model& model, Data& data, const VecRef& q, const VecRef& params,
                ParameterLayout layout, MatOut M) noexcept;

/// ddq = A(q)^-1 (tau - b(q, dq) - c(q) - friction - offsets). Returns false, leaving ddq
/// unchanged, when A(q) is not positive definite for these parameters.
bool forwardDynamics(const Model& model, Data& data, const VecRef& q, const VecRef& dq,
                     const VecRef& tau, const VecRef& params, ParameterLayout layout,
                     VecOut ddq) noexcept;

/// Throws ModelError when the layout's rotor inertia or friction act on the motors
/// (Model::motorSide) and the transmission has not one motor per joint.
void checkDriveSide(const Model& model, ParameterLayout layout);

/// Throws std::invalid_argument naming the argument whose size does not fit the model (and
/// checkDriveSide's ModelError).
void checkSizes(const Model& model, ParameterLayout layout, long q, long dq, long ddq, long params);

}  // namespace mindyn
