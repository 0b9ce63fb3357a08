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

/// sign(x) with sign(0) = 0 (Coulomb friction at rest).
inline double sgn(double x) { return x > 0.0 ? 1.0 : (x < 0.0 ? -1.0 : 0.0); }

}  // namespace mindyn::detail
