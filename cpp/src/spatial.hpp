// Small 3-D helpers shared by the implementation files (not installed).
#pragma once

#include <Eigen/Core>

namespace mindyn::detail {

/// [w]x: skew(w) v = w x v.
inline Eigen::Matrix3d skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d m;
  m << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return m;
}

/// I w = inertiaMap(w) [XX XY XZ YY YZ ZZ] for the symmetric tensor of model.hpp.
inline Eigen::Matrix<double, 3, 6> inertiaMap(const Eigen::Vector3d& w) {
  Eigen::Matrix<double, 3, 6> L;
  L << w.x(), w.y(), w.z(), 0.0, 0.0, 0.0,  //
      0.0, w.x(), 0.0, w.y(), w.z(), 0.0,   //
      0.0, 0.0, w.x(), 0.0, w.y(), w.z();
  return L;
}

/// Motion cross product a x b of two spatial vectors (angular; linear).
inline Eigen::Matrix<double, 6, 1> crossMotion(const Eigen::Matrix<double, 6, 1>& a,
                                               const Eigen::Matrix<double, 6, 1>& b) {
  Eigen::Matrix<double, 6, 1> c;
  c.head<3>() = a.head<3>().cross(b.head<3>());
  c.tail<3>() = a.head<3>().cross(b.tail<3>()) + a.tail<3>().cross(b.head<3>());
  return c;
}

/// Re-expresses a block of force-like spatial vectors (wrenches or momenta; columns of F, in the
/// frame of link k about its origin) in link k-1 about its origin, given the rotation R and the
/// origin p of link k in link k-1: n' = R n + p x (R f), f' = R f.
inline void carryToParent(const Eigen::Matrix3d& R, const Eigen::Vector3d& p,
                          Eigen::Matrix<double, 6, 10>& F) {
  const Eigen::Matrix<double, 3, 10> fr = R * F.bottomRows<3>();
  F.topRows<3>() = R * F.topRows<3>() + skew(p) * fr;
  F.bottomRows<3>() = fr;
}

/// sign(x) with sign(0) = 0 (Coulomb friction at rest).
inline double sgn(double x) { return x > 0.0 ? 1.0 : (x < 0.0 ? -1.0 : 0.0); }

}  // namespace mindyn::detail
