// The spatial algebra of the dynamics, the Slotine-Li recursion and the inverse kinematics, in one
// place: cross-product matrices, the inertia map of the classical parameters, motion and force
// cross products, the carry of wrenches from a link to its parent, and the pose error of two
// frames. Spatial vectors are (angular; linear) about a frame origin in that frame's axes, as in
// dynamics.hpp. Everything here is inline, allocates nothing and throws nothing.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace mindyn {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kTwoPi = 2 * kPi;

using Vector6d = Eigen::Matrix<double, 6, 1>;

/// [w]x: skew(w) v = w x v.
inline Eigen::Matrix3d skew(const Eigen::Vector3d& w) noexcept {
  Eigen::Matrix3d m;
  m << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return m;
}

/// I w = inertiaMap(w) [XX XY XZ YY YZ ZZ] for the symmetric tensor of model.hpp.
inline Eigen::Matrix<double, 3, 6> inertiaMap(const Eigen::Vector3d& w) noexcept {
  Eigen::Matrix<double, 3, 6> L;
  L << w.x(), w.y(), w.z(), 0.0, 0.0, 0.0,  //
      0.0, w.x(), 0.0, w.y(), w.z(), 0.0,   //
      0.0, 0.0, w.x(), 0.0, w.y(), w.z();
  return L;
}

/// Motion cross product a x b of two spatial motion vectors.
inline Vector6d crossMotion(const Vector6d& a, const Vector6d& b) noexcept {
  Vector6d c;
  c.head<3>() = a.head<3>().cross(b.head<3>());
  c.tail<3>() = a.head<3>().cross(b.tail<3>()) + a.tail<3>().cross(b.head<3>());
  return c;
}

/// Force cross product v x* f of a motion vector and a force vector.
inline Vector6d crossForce(const Vector6d& v, const Vector6d& f) noexcept {
  Vector6d r;
  r.head<3>() = v.head<3>().cross(f.head<3>()) + v.tail<3>().cross(f.tail<3>());
  r.tail<3>() = v.head<3>().cross(f.tail<3>());
  return r;
}

/// The 6x6 matrix of v x* .
inline Eigen::Matrix<double, 6, 6> crossForceMatrix(const Vector6d& v) noexcept {
  Eigen::Matrix<double, 6, 6> X = Eigen::Matrix<double, 6, 6>::Zero();
  X.topLeftCorner<3, 3>() = skew(v.head<3>());
  X.topRightCorner<3, 3>() = skew(v.tail<3>());
  X.bottomRightCorner<3, 3>() = skew(v.head<3>());
  return X;
}

/// The one motion carry of the forward recursions: a motion vector u of link k-1 (about its
/// origin, in its axes) expressed in link k, given the rotation R and the origin p of link k in
/// link k-1: w' = R^T w, v' = R^T (v + w x p).
inline Vector6d motionToChild(const Eigen::Matrix3d& R, const Eigen::Vector3d& p,
                              const Vector6d& u) noexcept {
  Vector6d r;
  r.head<3>() = R.transpose() * u.head<3>();
  r.tail<3>() = R.transpose() * (u.tail<3>() + u.head<3>().cross(p));
  return r;
}

/// The one wrench carry of the backward recursions: re-expresses force-like spatial vectors
/// (wrenches or momenta, the columns of F: 6 x 1 or a 6 x 10 regressor block, in the frame of
/// link k about its origin) in link k-1 about its origin, given the rotation R and the origin p
/// of link k in link k-1: n' = R n + p x (R f), f' = R f. The result is written to `out`, or
/// added to it with Add; `out` may be F itself (carried in place; not with Add).
template <bool Add = false, int Cols>
inline void carryToParent(const Eigen::Matrix3d& R, const Eigen::Vector3d& p,
                          const Eigen::Matrix<double, 6, Cols>& F,
                          Eigen::Matrix<double, 6, Cols>& out) noexcept {
  const Eigen::Matrix<double, 3, Cols> fr = R * F.template bottomRows<3>();
  auto top = out.template topRows<3>();
  if constexpr (Cols == 1) {
    if constexpr (Add)
      top += R * F.template topRows<3>() + p.cross(fr);
    else
      top = R * F.template topRows<3>() + p.cross(fr);
  } else {
    if constexpr (Add)
      top += R * F.template topRows<3>() + skew(p) * fr;
    else
      top = R * F.template topRows<3>() + skew(p) * fr;
  }
  if constexpr (Add)
    out.template bottomRows<3>() += fr;
  else
    out.template bottomRows<3>() = fr;
}

/// sign(x) with sign(0) = 0 (Coulomb friction at rest).
inline double sgn(double x) noexcept { return x > 0.0 ? 1.0 : (x < 0.0 ? -1.0 : 0.0); }

/// Rotation vector of R (the log map of SO(3)), accurate near 0 and pi; returns the angle.
inline double rotationLog(const Eigen::Matrix3d& R, Eigen::Ref<Eigen::Vector3d> out) noexcept {
  const double c = std::max(-1.0, std::min(1.0, 0.5 * (R.trace() - 1.0)));
  const Eigen::Vector3d w(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
  const double s = 0.5 * w.norm();
  const double angle = std::atan2(s, c);
  if (s > 1e-6) {
    out = w * (angle / (2.0 * s));
  } else if (c > 0.0) {
    out = 0.5 * w;  // small angle: sin(angle) ~ angle
  } else {
    // angle ~ pi: the axis from the symmetric part, R ~ 2 a a^T - I
    const Eigen::Matrix3d B = 0.5 * (R + R.transpose()) + Eigen::Matrix3d::Identity();
    int i;
    B.diagonal().maxCoeff(&i);
    Eigen::Vector3d a = B.col(i).normalized();
    if (a.dot(w) < 0) a = -a;
    out = angle * a;
  }
  return angle;
}

/// The pose error: the twist e = (p_target - p, rotation vector of R_target R^T), in the base
/// frame, that moves the frame T onto `target`; returns max |e_i|.
inline double poseError(const Eigen::Isometry3d& T, const Eigen::Isometry3d& target,
                        Eigen::Ref<Vector6d> e) noexcept {
  e.head<3>() = target.translation() - T.translation();
  rotationLog(target.linear() * T.linear().transpose(), e.tail<3>());
  return e.cwiseAbs().maxCoeff();
}

/// Its measure: the norm of the SE(3) logarithm of target^-1 T, sqrt(|v|^2 + |w|^2) with
/// (v, w) = log6 (metres and radians, Pinocchio's log6(oMdes.actInv(oMq)) norm).
inline double logError(const Eigen::Isometry3d& T, const Eigen::Isometry3d& target) noexcept {
  // M = target^-1 T; log6(M) = (V(w)^-1 p, w) with w = log3(R) of angle t and
  // V^-1 = I - W / 2 + k W^2, k = (1 - t sin t / (2 (1 - cos t))) / t^2 (1/12 + t^2/720 near 0).
  const Eigen::Matrix3d R = target.linear().transpose() * T.linear();
  const Eigen::Vector3d p = target.linear().transpose() * (T.translation() - target.translation());
  Eigen::Vector3d w;
  const double t = rotationLog(R, w);
  const double k = t < 1e-4 ? 1.0 / 12 + t * t / 720
                            : (1.0 - t * std::sin(t) / (2.0 * (1.0 - std::cos(t)))) / (t * t);
  const Eigen::Vector3d wp = w.cross(p);
  const Eigen::Vector3d v = p - 0.5 * wp + k * w.cross(wp);
  return std::sqrt(v.squaredNorm() + w.squaredNorm());
}

}  // namespace mindyn
