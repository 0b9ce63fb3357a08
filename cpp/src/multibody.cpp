#include "mindyn/multibody.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "body_terms.hpp"
#include "mindyn/spatial.hpp"

namespace mindyn {

namespace {

/// A motion vector of the frame moved by a joint, re-expressed in the link frame (post).
inline Vector6d toLink(const Joint& j, const Vector6d& u) noexcept {
  return motionToChild(j.post.linear(), j.post.translation(), u);
}

inline Vector6d angular(const Eigen::Vector3d& w) noexcept {
  Vector6d u;
  u << w, Eigen::Vector3d::Zero();
  return u;
}

inline Vector6d linear(const Eigen::Vector3d& l) noexcept {
  Vector6d u;
  u << Eigen::Vector3d::Zero(), l;
  return u;
}

/// The joint's rotation Rj and translation tj (J(q) in the joint frame) and, when `S` is
/// given, its motion subspace in the moved frame.
void jointMotion(const Joint& j, const double* q, Eigen::Matrix3d& Rj, Eigen::Vector3d& tj,
                 Matrix6d* S) noexcept {
  tj.setZero();
  Rj.setIdentity();
  const Eigen::Vector3d ex = Eigen::Vector3d::UnitX(), ey = Eigen::Vector3d::UnitY(),
                        ez = Eigen::Vector3d::UnitZ();
  switch (j.type) {
    case JointType::Revolute:
      Rj = Eigen::AngleAxisd(q[0], j.axis).toRotationMatrix();
      if (S) S->col(0) = angular(j.axis);
      break;
    case JointType::Prismatic:
      tj = j.axis * q[0];
      if (S) S->col(0) = linear(j.axis);
      break;
    case JointType::Spherical:
      Rj = Eigen::Quaterniond(q[3], q[0], q[1], q[2]).toRotationMatrix();
      if (S)
        for (int i = 0; i < 3; ++i) S->col(i) = angular(Eigen::Vector3d::Unit(i));
      break;
    case JointType::Universal: {
      const Eigen::Matrix3d R2 = Eigen::AngleAxisd(q[1], j.axis2).toRotationMatrix();
      Rj = Eigen::AngleAxisd(q[0], j.axis).toRotationMatrix() * R2;
      if (S) {
        S->col(0) = angular(R2.transpose() * j.axis);
        S->col(1) = angular(j.axis2);
      }
      break;
    }
    case JointType::Cylindrical:
      Rj = Eigen::AngleAxisd(q[1], j.axis).toRotationMatrix();
      tj = j.axis * q[0];
      if (S) {
        S->col(0) = linear(j.axis);
        S->col(1) = angular(j.axis);
      }
      break;
    case JointType::Planar:
      Rj << q[2], -q[3], 0.0, q[3], q[2], 0.0, 0.0, 0.0, 1.0;
      tj << q[0], q[1], 0.0;
      if (S) {
        S->col(0) = linear(ex);
        S->col(1) = linear(ey);
        S->col(2) = angular(ez);
      }
      break;
    case JointType::FreeFlyer:
      Rj = Eigen::Quaterniond(q[6], q[3], q[4], q[5]).toRotationMatrix();
      tj << q[0], q[1], q[2];
      if (S)
        for (int i = 0; i < 3; ++i) {
          S->col(i) = linear(Eigen::Vector3d::Unit(i));
          S->col(3 + i) = angular(Eigen::Vector3d::Unit(i));
        }
      break;
  }
}

inline int blockStart(int k) { return 10 * k; }

/// The bias dS/dt u of joint k's motion subspace along the velocity v, applied to u (v itself
/// in the dynamics, the reference velocity in the Slotine-Li regressor), in link k's frame: zero
/// but for the universal joint, whose first column R2^T axis turns with the second coordinate,
/// d/dt (R2^T axis) = -(axis2 x R2^T axis) dq2 in the moved frame.
inline Vector6d jointBias(const Model& model, const MultibodyData& data, int k, const VecRef& v,
                          const VecRef& u) noexcept {
  const Joint& j = model.joints[k];
  if (j.type != JointType::Universal) return Vector6d::Zero();
  const int iv = data.iv[k];
  const Eigen::Vector3d s0 = j.post.linear() * data.S[k].col(0).head<3>();
  return toLink(j, angular(-u[iv] * v[iv + 1] * j.axis2.cross(s0)));
}

/// Spatial velocities and accelerations of every link (data.v, a); needs forwardKinematics.
void motionPass(const Model& model, MultibodyData& data, const VecRef& v, const VecRef& a,
                bool with_gravity) noexcept {
  Vector6d a_base = Vector6d::Zero();
  if (with_gravity) a_base.tail<3>() = -model.gravity;
  for (int k = 0; k < data.n; ++k) {
    const int d = data.dof[k], iv = data.iv[k];
    const auto S = data.S[k].leftCols(d);
    const Vector6d aj = S * a.segment(iv, d) + jointBias(model, data, k, v, v);
    const int pk = std::max(model.parent(k), 0);  // the base: not read
    linkMotion(model.parent(k) >= 0, data.R[k], data.p[k], data.v[pk], data.a[pk], a_base,
               S * v.segment(iv, d), aj, data.v[k], data.a[k]);
  }
}

/// Joint forces from the link motions (data.v, a) and the classical parameters.
void forcePass(const Model& model, MultibodyData& data, const VecRef& params, VecOut tau) noexcept {
  for (int k = 0; k < data.n; ++k)
    data.f[k] = bodyWrench(params.segment<10>(blockStart(k)), data.v[k], data.a[k]);
  for (int k = data.n - 1; k >= 0; --k) {
    tau.segment(data.iv[k], data.dof[k]).noalias() =
        data.S[k].leftCols(data.dof[k]).transpose() * data.f[k];
    const int pk = model.parent(k);
    if (pk >= 0) carryToParent<true>(data.R[k], data.p[k], data.f[k], data.f[pk]);
  }
}

}  // namespace

MultibodyData::MultibodyData(const Model& model)
    : n(model.nq()),
      nq(model.configSize()),
      nv(model.velocitySize()),
      iq(n),
      iv(n),
      dof(n),
      S(n, Matrix6d::Zero()),
      c(n, Vector6d::Zero()),
      R(n),
      R0(n),
      p(n),
      p0(n),
      v(n),
      a(n),
      f(n),
      vr(n, Vector6d::Zero()),
      ar(n, Vector6d::Zero()),
      zeros(Eigen::VectorXd::Zero(nv)),
      unit(Eigen::VectorXd::Zero(nv)),
      tmp(Eigen::VectorXd::Zero(nv)),
      M(Eigen::MatrixXd::Zero(nv, nv)),
      Yw(Eigen::MatrixXd::Zero(nv, 10 * n)),
      llt(nv) {
  for (int k = 0, i = 0, j = 0; k < n; ++k) {
    iq[k] = i;
    iv[k] = j;
    dof[k] = model.joints[k].nv();
    i += model.joints[k].nq();
    j += dof[k];
  }
}

void forwardKinematics(const Model& model, MultibodyData& data, const VecRef& q) noexcept {
  for (int k = 0; k < data.n; ++k) {
    const Joint& j = model.joints[k];
    Eigen::Matrix3d Rj;
    Eigen::Vector3d tj;
    Matrix6d SJ;
    jointMotion(j, q.data() + data.iq[k], Rj, tj, &SJ);
    for (int i = 0; i < data.dof[k]; ++i) data.S[k].col(i) = toLink(j, SJ.col(i));
    data.R[k] = j.pre.linear() * Rj * j.post.linear();
    data.p[k] = j.pre.translation() + j.pre.linear() * (tj + Rj * j.post.translation());
    const int pk = std::max(model.parent(k), 0);  // the base: not read
    placeInBase(model.parent(k) >= 0, data.R0[pk], data.p0[pk], data.R[k], data.p[k], data.R0[k],
                data.p0[k]);
  }
}

void frameJacobian(const Model& model, MultibodyData& data, const VecRef& q, int link,
                   const Eigen::Isometry3d& placement, ReferenceFrame frame, MatOut J) noexcept {
  forwardKinematics(model, data, q);
  const Eigen::Vector3d o = data.p0[link] + data.R0[link] * placement.translation();
  // the rows' axes in the base frame: the base's (identity) or the frame's
  const Eigen::Matrix3d Rt = frame == ReferenceFrame::Local
                                 ? Eigen::Matrix3d((data.R0[link] * placement.linear()).transpose())
                                 : Eigen::Matrix3d::Identity();
  J.setZero();
  for (int k = link; k >= 0; k = model.parent(k))
    for (int i = 0; i < data.dof[k]; ++i) {
      const Eigen::Vector3d w = data.R0[k] * data.S[k].col(i).head<3>();
      const Eigen::Vector3d v = data.R0[k] * data.S[k].col(i).tail<3>() + w.cross(o - data.p0[k]);
      J.col(data.iv[k] + i).head<3>().noalias() = Rt * v;
      J.col(data.iv[k] + i).tail<3>().noalias() = Rt * w;
    }
}

void inverseDynamics(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& v,
                     const VecRef& a, const VecRef& params, VecOut tau) noexcept {
  forwardKinematics(model, data, q);
  motionPass(model, data, v, a, true);
  forcePass(model, data, params, tau);
}

void regressor(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& v,
               const VecRef& a, MatOut W) noexcept {
  forwardKinematics(model, data, q);
  motionPass(model, data, v, a, true);
  W.setZero();
  for (int j = 0; j < data.n; ++j) {
    auto& F = data.F;
    bodyRegressor(data.v[j], data.a[j], F);
    for (int k = j; k >= 0; k = model.parent(k)) {
      W.block(data.iv[k], blockStart(j), data.dof[k], 10).noalias() =
          data.S[k].leftCols(data.dof[k]).transpose() * F;
      if (model.parent(k) >= 0) carryToParent(data.R[k], data.p[k], F, F);
    }
  }
}

void slotineLiRegressor(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& v,
                        const VecRef& vr, const VecRef& ar, MatOut Y) noexcept {
  forwardKinematics(model, data, q);
  motionPass(model, data, v, data.zeros, false);  // the actual link velocities data.v
  Vector6d a_base = Vector6d::Zero();
  a_base.tail<3>() = -model.gravity;
  for (int k = 0; k < data.n; ++k) {
    const int d = data.dof[k], iv = data.iv[k];
    const auto S = data.S[k].leftCols(d);
    const Vector6d aj = S * ar.segment(iv, d) + jointBias(model, data, k, v, vr);
    const Vector6d sj = S * vr.segment(iv, d);
    const int pk = model.parent(k);
    if (pk < 0) {
      data.vr[k] = sj;
      data.ar[k] = motionToChild(data.R[k], data.p[k], a_base);
    } else {
      data.vr[k] = motionToChild(data.R[k], data.p[k], data.vr[pk]) + sj;
      data.ar[k] = motionToChild(data.R[k], data.p[k], data.ar[pk]);
    }
    data.ar[k] += aj + crossMotion(data.v[k], sj);
  }
  Y.setZero();
  for (int k = 0; k < data.n; ++k) {
    const Vector6d &vk = data.v[k], &vrk = data.vr[k];
    auto& F = data.F;
    F = inertiaRegressor(data.ar[k] - 0.5 * crossMotion(vk, vrk)) +
        0.5 * (crossForceMatrix(vk) * inertiaRegressor(vrk) +
               crossForceMatrix(vrk) * inertiaRegressor(vk));
    for (int i = k; i >= 0; i = model.parent(i)) {
      Y.block(data.iv[i], blockStart(k), data.dof[i], 10).noalias() =
          data.S[i].leftCols(data.dof[i]).transpose() * F;
      if (model.parent(i) >= 0) carryToParent(data.R[i], data.p[i], F, F);
    }
  }
}

void coriolisMatrix(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& v,
                    const VecRef& params, MatOut C) noexcept {
  // column i: the response to the reference velocity e_i, the gravity (vr = 0) taken off
  Eigen::MatrixXd& Y = data.Yw;
  slotineLiRegressor(model, data, q, v, data.zeros, data.zeros, Y);
  data.tmp.noalias() = Y * params;
  data.unit.setZero();
  for (int i = 0; i < data.nv; ++i) {
    data.unit[i] = 1.0;
    slotineLiRegressor(model, data, q, v, data.unit, data.zeros, Y);
    C.col(i).noalias() = Y * params;
    C.col(i) -= data.tmp;
    data.unit[i] = 0.0;
  }
}

void massMatrix(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& params,
                MatOut M) noexcept {
  forwardKinematics(model, data, q);
  data.unit.setZero();
  for (int i = 0; i < data.nv; ++i) {
    data.unit[i] = 1.0;
    motionPass(model, data, data.zeros, data.unit, false);
    forcePass(model, data, params, M.col(i));
    data.unit[i] = 0.0;
  }
  for (int i = 0; i < data.nv; ++i)
    for (int j = 0; j < i; ++j) M(i, j) = M(j, i) = 0.5 * (M(i, j) + M(j, i));
}

bool forwardDynamics(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& v,
                     const VecRef& tau, const VecRef& params, VecOut a) noexcept {
  massMatrix(model, data, q, params, data.M);
  data.llt.compute(data.M);
  if (data.llt.info() != Eigen::Success) return false;
  motionPass(model, data, v, data.zeros, true);
  forcePass(model, data, params, data.tmp);
  data.tmp = tau - data.tmp;
  data.llt.solveInPlace(data.tmp);
  a = data.tmp;
  return true;
}

double kineticEnergy(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& v,
                     const VecRef& params) noexcept {
  forwardKinematics(model, data, q);
  motionPass(model, data, v, data.zeros, false);
  double K = 0.0;
  for (int k = 0; k < data.n; ++k) {
    const auto pk = params.segment<10>(blockStart(k));
    const Eigen::Vector3d w = data.v[k].head<3>();
    const Eigen::Vector3d vl = data.v[k].tail<3>();
    K += 0.5 * w.dot(inertiaTensor(pk) * w) + vl.dot(w.cross(pk.segment<3>(6))) +
         0.5 * pk[9] * vl.squaredNorm();
  }
  return K;
}

Vector6d momentum(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& v,
                  const VecRef& params) noexcept {
  forwardKinematics(model, data, q);
  motionPass(model, data, v, data.zeros, false);
  Vector6d h = Vector6d::Zero();  // (angular; linear) about the base origin, base axes
  for (int k = 0; k < data.n; ++k) {
    const Vector6d hk = inertiaRegressor(data.v[k]) * params.segment<10>(blockStart(k));
    carryToParent<true>(data.R0[k], data.p0[k], hk, h);
  }
  Vector6d out;
  out << h.tail<3>(), h.head<3>();
  return out;
}

double potentialEnergy(const Model& model, MultibodyData& data, const VecRef& q,
                       const VecRef& params) noexcept {
  forwardKinematics(model, data, q);
  double P = 0.0;
  for (int k = 0; k < data.n; ++k) {
    const auto pk = params.segment<10>(blockStart(k));
    P -= model.gravity.dot(pk[9] * data.p0[k] + data.R0[k] * pk.segment<3>(6));
  }
  return P;
}

void energyRegressors(const Model& model, MultibodyData& data, const VecRef& q, const VecRef& v,
                      VecOut wK, VecOut wP) noexcept {
  forwardKinematics(model, data, q);
  motionPass(model, data, v, data.zeros, false);
  wK.setZero();
  wP.setZero();
  const Eigen::Vector3d& g = model.gravity;
  for (int k = 0; k < data.n; ++k) {
    const int c = blockStart(k);
    linkEnergyTerms(data.v[k], data.R0[k], data.p0[k], g, wK.segment<10>(c), wP.segment<10>(c));
  }
}

void randomConfiguration(const Model& model, std::mt19937& rng, Eigen::VectorXd& q) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> gauss;
  int i = 0;
  for (const Joint& j : model.joints) {
    auto unitQuaternion = [&](int at) {
      Eigen::Vector4d x;
      do x << gauss(rng), gauss(rng), gauss(rng), gauss(rng);
      while (x.norm() < 1e-3);
      q.segment<4>(at) = x.normalized();
    };
    switch (j.type) {
      case JointType::Revolute:
      case JointType::Prismatic: {
        const JointLimits& l = j.limits;
        const bool bounded = std::isfinite(l.lower) && std::isfinite(l.upper);
        const double lo = bounded ? l.lower : (j.type == JointType::Revolute ? -kPi : -1.0);
        const double hi = bounded ? l.upper : -lo;
        q[i] = lo + (hi - lo) * 0.5 * (u(rng) + 1.0);
        break;
      }
      case JointType::Spherical:
        unitQuaternion(i);
        break;
      case JointType::Universal:
        q[i] = kPi * u(rng);
        q[i + 1] = kPi * u(rng);
        break;
      case JointType::Cylindrical:
        q[i] = u(rng);
        q[i + 1] = kPi * u(rng);
        break;
      case JointType::Planar: {
        const double t = kPi * u(rng);
        q.segment<4>(i) << u(rng), u(rng), std::cos(t), std::sin(t);
        break;
      }
      case JointType::FreeFlyer:
        q.segment<3>(i) << u(rng), u(rng), u(rng);
        unitQuaternion(i + 3);
        break;
    }
    i += j.nq();
  }
}

void checkMultibodySizes(const Model& model, long q, long v, long a, long params) {
  const auto need = [](const char* what, long got, long want, const char* of) {
    if (got >= 0 && got != want)
      throw std::invalid_argument(std::string(what) + " has " + std::to_string(got) +
                                  " entries; the model's " + of + " has " + std::to_string(want));
  };
  need("q", q, model.configSize(), "configuration");
  need("v", v, model.velocitySize(), "velocity");
  need("a", a, model.velocitySize(), "velocity");
  need("params", params, 10L * model.nq(), "inertial parameter vector");
}

}  // namespace mindyn
