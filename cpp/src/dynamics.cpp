#include "mindyn/dynamics.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "body_terms.hpp"
#include "drive_terms.hpp"
#include "mindyn/spatial.hpp"

namespace mindyn {

namespace {

inline int blockStart(ParameterLayout layout, int k) { return k * layout.perLink(); }

}  // namespace

void forwardKinematics(const Model& model, Data& data, const VecRef& q) noexcept {
  for (int k = 0; k < data.n; ++k) {
    const Joint& j = model.joints[k];
    Eigen::Matrix3d Rj;
    Eigen::Vector3d tj;
    if (j.type == JointType::Revolute) {
      Rj = Eigen::AngleAxisd(q[k], j.axis).toRotationMatrix();
      tj = Rj * j.post.translation();
    } else {
      Rj.setIdentity();
      tj = j.axis * q[k] + j.post.translation();
    }
    data.R[k] = j.pre.linear() * Rj * j.post.linear();
    data.p[k] = j.pre.translation() + j.pre.linear() * tj;
    const int pk = std::max(model.parent(k), 0);  // the base: not read
    placeInBase(model.parent(k) >= 0, data.R0[pk], data.p0[pk], data.R[k], data.p[k], data.R0[k],
                data.p0[k]);
  }
}

namespace {

// Spatial velocities and accelerations; needs forwardKinematics.
void motionPass(const Model& model, Data& data, const VecRef& dq, const VecRef& ddq,
                bool with_gravity) noexcept {
  // The base: at rest, accelerating upwards by -g to account for gravity.
  Vector6d a_base = Vector6d::Zero();
  if (with_gravity) a_base.tail<3>() = -model.gravity;
  for (int k = 0; k < data.n; ++k) {
    const Vector6d& S = data.S[k];
    const int pk = std::max(model.parent(k), 0);  // the base: not read
    linkMotion(model.parent(k) >= 0, data.R[k], data.p[k], data.v[pk], data.a[pk], a_base,
               S * dq[k], S * ddq[k], data.v[k], data.a[k]);
  }
}

// Joint torques from the kinematic quantities and a parameter vector.
void forcePass(const Model& model, Data& data, const VecRef& dq, const VecRef& ddq,
               const VecRef& params, ParameterLayout layout, bool joint_terms,
               VecOut tau) noexcept {
  const int n = data.n;
  for (int k = 0; k < n; ++k)
    data.f[k] = bodyWrench(params.segment<10>(blockStart(layout, k)), data.v[k], data.a[k]);
  for (int k = n - 1; k >= 0; --k) {
    tau[k] = data.S[k].dot(data.f[k]);
    // f[k] is complete: every child of link k has a larger index and was carried into it.
    const int pk = model.parent(k);
    if (pk >= 0) carryToParent<true>(data.R[k], data.p[k], data.f[k], data.f[pk]);
  }
  if (joint_terms) drive::addDriveTorques(model, layout, params, dq, ddq, tau);
}

}  // namespace

void computeKinematics(const Model& model, Data& data, const VecRef& q, const VecRef& dq,
                       const VecRef& ddq, bool with_gravity) noexcept {
  forwardKinematics(model, data, q);
  motionPass(model, data, dq, ddq, with_gravity);
}

void inverseDynamics(const Model& model, Data& data, const VecRef& q, const VecRef& dq,
                     const VecRef& ddq, const VecRef& params, ParameterLayout layout,
                     VecOut tau) noexcept {
  computeKinematics(model, data, q, dq, ddq, true);
  forcePass(model, data, dq, ddq, params, layout, true, tau);
  drive::addOffsets(layout, params, tau);
}

void gravityTorque(const Model& model, Data& data, const VecRef& q, const VecRef& params,
                   ParameterLayout layout, VecOut tau) noexcept {
  computeKinematics(model, data, q, data.zeros, data.zeros, true);
  forcePass(model, data, data.zeros, data.zeros, params, layout, false, tau);
}

void regressor(const Model& model, Data& data, const VecRef& q, const VecRef& dq, const VecRef& ddq,
               ParameterLayout layout, MatOut W) noexcept {
  computeKinematics(model, data, q, dq, ddq, true);
  const int n = data.n;
  W.setZero();
  for (int j = 0; j < n; ++j) {
    Matrix6x10& F = data.F;
    bodyRegressor(data.v[j], data.a[j], F);
    const int c0 = blockStart(layout, j);
    // Link j's wrench block reaches the joints that support it: j and its ancestors.
    for (int k = j; k >= 0; k = model.parent(k)) {
      W.block<1, 10>(k, c0).noalias() = data.S[k].transpose() * F;
      if (model.parent(k) >= 0) carryToParent(data.R[k], data.p[k], F, F);  // to the parent link
    }
  }
  drive::driveColumns(model, layout, dq, ddq, W);
  drive::offsetColumns(layout, W);
}

void energyRegressors(const Model& model, Data& data, const VecRef& q, const VecRef& dq,
                      ParameterLayout layout, VecOut wK, VecOut wP) noexcept {
  computeKinematics(model, data, q, dq, data.zeros, false);
  wK.setZero();
  wP.setZero();
  const Eigen::Vector3d& g = model.gravity;
  for (int k = 0; k < data.n; ++k) {
    const int c = blockStart(layout, k);
    linkEnergyTerms(data.v[k], data.R0[k], data.p0[k], g, wK.segment<10>(c), wP.segment<10>(c));
    if (layout.rotor) {
      const double v = drive::motorVelocity(model, k, dq);
      wK[layout.rotorIndex(k)] = 0.5 * v * v;
    }
  }
  // An offset's work Off_k q_k, so that differences over a window are the energy model's.
  if (layout.offset) wP.segment(layout.offsetIndex(data.n, 0), data.n) = q;
}

double kineticEnergy(const Model& model, Data& data, const VecRef& q, const VecRef& dq,
                     const VecRef& params, ParameterLayout layout) noexcept {
  computeKinematics(model, data, q, dq, data.zeros, false);
  double K = 0.0;
  for (int k = 0; k < data.n; ++k) {
    const auto pk = params.segment<10>(blockStart(layout, k));
    Eigen::Matrix3d I;
    I << pk[0], pk[1], pk[2], pk[1], pk[3], pk[4], pk[2], pk[4], pk[5];
    const Eigen::Vector3d w = data.v[k].head<3>();
    const Eigen::Vector3d vl = data.v[k].tail<3>();
    K += 0.5 * w.dot(I * w) + vl.dot(w.cross(pk.segment<3>(6))) + 0.5 * pk[9] * vl.squaredNorm();
    if (layout.rotor) {
      const double v = drive::motorVelocity(model, k, dq);
      K += 0.5 * params[layout.rotorIndex(k)] * v * v;
    }
  }
  return K;
}

double potentialEnergy(const Model& model, Data& data, const VecRef& q, const VecRef& params,
                       ParameterLayout layout) noexcept {
  forwardKinematics(model, data, q);
  double P = 0.0;
  for (int k = 0; k < data.n; ++k) {
    const auto pk = params.segment<10>(blockStart(layout, k));
    P -= model.gravity.dot(pk[9] * data.p0[k] + data.R0[k] * pk.segment<3>(6));
  }
  return P;
}

void massMatrix(const Model& model, Data& data, const VecRef& q, const VecRef& params,
                ParameterLayout layout, MatOut M) noexcept {
  forwardKinematics(model, data, q);
  data.unit.setZero();
  for (int j = 0; j < data.n; ++j) {
    data.unit[j] = 1.0;
    motionPass(model, data, data.zeros, data.unit, false);
    forcePass(model, data, data.zeros, data.unit, params, layout, true, M.col(j));
    data.unit[j] = 0.0;
  }
  // The columns are exact; symmetrise the rounding.
  for (int i = 0; i < data.n; ++i)
    for (int j = 0; j < i; ++j) M(i, j) = M(j, i) = 0.5 * (M(i, j) + M(j, i));
}

bool forwardDynamics(const Model& model, Data& data, const VecRef& q, const VecRef& dq,
                     const VecRef& tau, const VecRef& params, ParameterLayout layout,
                     VecOut ddq) noexcept {
  massMatrix(model, data, q, params, layout, data.M);
  data.llt.compute(data.M);
  if (data.llt.info() != Eigen::Success) return false;
  motionPass(model, data, dq, data.zeros, true);
  forcePass(model, data, dq, data.zeros, params, layout, true, data.tmp);
  drive::addOffsets(layout, params, data.tmp);
  data.tmp = tau - data.tmp;
  data.llt.solveInPlace(data.tmp);
  ddq = data.tmp;
  return true;
}

void checkFrictionLayout(const Model& model, ParameterLayout layout) {
  if (layout.friction && layout.friction_columns != model.friction_model.columns())
    throw std::invalid_argument(
        "the parameter layout has " + std::to_string(layout.friction_columns) +
        " friction columns per joint; the model's " + toString(model.friction_model.kind) +
        " friction model has " + std::to_string(model.friction_model.columns()));
  try {
    model.friction_model.validate(model.nq());
  } catch (const ModelError& e) {
    throw std::invalid_argument(e.what());
  }
}

void checkSizes(const Model& model, ParameterLayout layout, long q, long dq, long ddq,
                long params) {
  checkFrictionLayout(model, layout);
  const long n = model.nq();
  auto need = [n](const char* what, long got) {
    if (got >= 0 && got != n)
      throw std::invalid_argument(std::string(what) + " has " + std::to_string(got) +
                                  " entries; the model has " + std::to_string(n) + " joints");
  };
  need("q", q);
  need("dq", dq);
  need("ddq", ddq);
  checkDriveSide(model, layout);
  if (params >= 0 && params != layout.size(static_cast<int>(n)))
    throw std::invalid_argument("params has " + std::to_string(params) + " entries; expected " +
                                std::to_string(layout.size(static_cast<int>(n))) +
                                " for this parameter layout");
}

void checkDriveSide(const Model& model, ParameterLayout layout) {
  if (!model.motorSide() || (!layout.rotor && !layout.friction) ||
      model.transmission.nm() == model.nq())
    return;
  throw ModelError(model.name + " has " + std::to_string(model.transmission.nm()) + " motors for " +
                   std::to_string(model.nq()) +
                   " joints: rotor inertia and friction on the motors need one motor per joint; "
                   "put them on the joints (drive side 'joint')");
}

}  // namespace mindyn
