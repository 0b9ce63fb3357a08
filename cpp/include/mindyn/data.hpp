// Per-call workspace of the dynamics algorithms, the Slotine-Li functions and the IK chain. Built
// once from a Model; after that the algorithms write into it and allocate nothing. One thread
// at a time: every thread that computes uses a Data of its own.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <vector>

#include "mindyn/model.hpp"

namespace mindyn {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6x10 = Eigen::Matrix<double, 6, 10>;

struct Data {
  explicit Data(const Model& model);

  int n;
  // Constant per model: joint screw axis expressed in the link frame, (angular; linear).
  std::vector<Vector6d> S;
  // Per link, filled by the kinematic pass: rotation and origin of link k in link k-1 ...
  std::vector<Eigen::Matrix3d> R;
  std::vector<Eigen::Vector3d> p;
  // ... and of link k in the base frame.
  std::vector<Eigen::Matrix3d> R0;
  std::vector<Eigen::Vector3d> p0;
  // Spatial velocity, spatial acceleration (gravity included as a base acceleration) and the
  // force transmitted by joint k, all in link-k coordinates, about the link origin.
  std::vector<Vector6d> v, a, f;
  // Regressor work: one 6x10 block.
  Matrix6x10 F;

  Eigen::VectorXd zeros, unit, tmp;  // n
  Eigen::MatrixXd M;                 // n x n
  Eigen::LLT<Eigen::MatrixXd> llt;
};

}  // namespace mindyn
