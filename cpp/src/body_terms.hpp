// The per-link terms of the Newton-Euler passes, in one place for the single-DOF dynamics
// (dynamics.cpp) and the multibody ones (multibody.cpp): a link's wrench from its classical
// parameters and motion, the same as a linear map of the parameters, a link's pose in the
// base frame, and its energies as linear maps of the parameters. Spatial vectors (angular; linear)
// as in spatial.hpp; nothing allocates or throws.
#pragma once

#include <Eigen/Core>

#include "mindyn/spatial.hpp"

namespace mindyn {

/// The wrench f = I a + v x* (I v) a link of ten classical parameters `p` (XX .. M about its
/// origin, its axes) needs for its spatial velocity v and acceleration a (gravity included in a),
/// in its frame about its origin: the one body term of the Newton-Euler passes.
template <class P>
inline Vector6d bodyWrench(const P& p, const Vector6d& v, const Vector6d& a) noexcept {
  Eigen::Matrix3d I;
  I << p[0], p[1], p[2], p[1], p[3], p[4], p[2], p[4], p[5];
  const Eigen::Vector3d h = p.template segment<3>(6);
  const Eigen::Vector3d w = v.head<3>();
  const Eigen::Vector3d aw = a.head<3>();
  const Eigen::Vector3d b = a.tail<3>() + w.cross(v.tail<3>());
  Vector6d f;
  f.head<3>() = I * aw + w.cross(I * w) - b.cross(h);
  f.tail<3>() = p[9] * b + aw.cross(h) + w.cross(w.cross(h));
  return f;
}

/// The same wrench as a linear map of the ten parameters: bodyWrench(p, v, a) = F p.
inline void bodyRegressor(const Vector6d& v, const Vector6d& a,
                          Eigen::Matrix<double, 6, 10>& F) noexcept {
  const Eigen::Vector3d w = v.head<3>();
  const Eigen::Vector3d aw = a.head<3>();
  const Eigen::Vector3d b = a.tail<3>() + w.cross(v.tail<3>());
  const Eigen::Matrix3d Sw = skew(w);
  F.setZero();
  F.block<3, 6>(0, 0) = inertiaMap(aw) + Sw * inertiaMap(w);
  F.block<3, 3>(0, 6) = -skew(b);
  F.block<3, 3>(3, 6) = skew(aw) + Sw * Sw;
  F.block<3, 1>(3, 9) = b;
}

/// I u = inertiaRegressor(u) [XX XY XZ YY YZ ZZ MX MY MZ M] for the spatial inertia of ten
/// classical parameters about the link origin: I (w, l) = (I_o w + h x l, M l - h x w).
inline Eigen::Matrix<double, 6, 10> inertiaRegressor(const Vector6d& u) noexcept {
  Eigen::Matrix<double, 6, 10> K = Eigen::Matrix<double, 6, 10>::Zero();
  K.block<3, 6>(0, 0) = inertiaMap(u.head<3>());
  K.block<3, 3>(0, 6) = -skew(u.tail<3>());
  K.block<3, 3>(3, 6) = skew(u.head<3>());
  K.block<3, 1>(3, 9) = u.tail<3>();
  return K;
}

/// Link k's pose in the base frame from its pose (R, p) in its parent link, whose pose in the
/// base frame is (R0p, p0p), or from the base (`has_parent` false).
inline void placeInBase(bool has_parent, const Eigen::Matrix3d& R0p, const Eigen::Vector3d& p0p,
                        const Eigen::Matrix3d& R, const Eigen::Vector3d& p, Eigen::Matrix3d& R0,
                        Eigen::Vector3d& p0) noexcept {
  if (!has_parent) {
    R0 = R;
    p0 = p;
  } else {
    p0 = p0p + R0p * p;
    R0 = R0p * R;
  }
}

/// Link k's velocity v and acceleration a from its joint: those of its parent (v_parent,
/// a_parent) or of the base (at rest, accelerating by a_base) carried into link k (at R, p in
/// its parent), plus the joint's velocity vj and acceleration aj (S ddq and its bias) and the
/// motion cross product v x vj.
inline void linkMotion(bool has_parent, const Eigen::Matrix3d& R, const Eigen::Vector3d& p,
                       const Vector6d& v_parent, const Vector6d& a_parent, const Vector6d& a_base,
                       const Vector6d& vj, const Vector6d& aj, Vector6d& v, Vector6d& a) noexcept {
  if (has_parent) {
    v = motionToChild(R, p, v_parent) + vj;
    a = motionToChild(R, p, a_parent) + aj;
  } else {
    v = vj;
    a = motionToChild(R, p, a_base) + aj;
  }
  // a += v x vj (motion cross product, written out: no temporary)
  a.head<3>() += v.head<3>().cross(vj.head<3>());
  a.tail<3>() += v.head<3>().cross(vj.tail<3>()) + v.tail<3>().cross(vj.head<3>());
}

/// A link's kinetic and potential energy as linear maps of its ten classical parameters:
/// K = wK . p (wK from its spatial velocity v, its frame) and P = wP . p (wP from its pose R0,
/// p0 in the base frame and the gravity g there).
template <class K, class Pot>
inline void linkEnergyTerms(const Vector6d& v, const Eigen::Matrix3d& R0, const Eigen::Vector3d& p0,
                            const Eigen::Vector3d& g, K&& wK, Pot&& wP) noexcept {
  const Eigen::Vector3d w = v.head<3>();
  const Eigen::Vector3d vl = v.tail<3>();
  wK[0] = 0.5 * w.x() * w.x();
  wK[1] = w.x() * w.y();
  wK[2] = w.x() * w.z();
  wK[3] = 0.5 * w.y() * w.y();
  wK[4] = w.y() * w.z();
  wK[5] = 0.5 * w.z() * w.z();
  wK.template segment<3>(6) = vl.cross(w);
  wK[9] = 0.5 * vl.squaredNorm();
  wP.template segment<3>(6) = -(R0.transpose() * g);
  wP[9] = -g.dot(p0);
}

}  // namespace mindyn
