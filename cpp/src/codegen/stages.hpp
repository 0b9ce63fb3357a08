// The joint geometry as the generated recursion uses it: the constants of a joint's transforms
// cleaned of round-off (and, within kGeometrySnap, snapped to 0 or +-1), and every joint split
// into stages: the constant transform `pre`, the joint motion about/along the axis `u` through
// the stage origin, the constant transform `post` (x_parent = pre * motion * post * x_link).
// A DH/MDH angle offset theta is moved out of the constant transforms into the joint angle;
// the part of a constant translation along the joint axis goes to `pre` or `post` as a Plan
// says, as does the frame each link's wrench is formed in.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "mindyn/codegen/newton_euler.hpp"

namespace mindyn::codegen::internal {

// Within round-off of 0 or +-1: exactly that (rotations by multiples of 90 degrees leave 1e-17
// residues).
double roundOffClean(double x);

// The constants of the geometry as the recursion uses them: entries within kGeometrySnap of 0 are
// 0 (a truncated pi/2, 1.57079632679 in many URDF files, leaves 4.9e-12); an entry of a rotation
// or of an axis within kGeometrySnap of +-1 is +-1 only when the rest of its row and column
// became 0, so that a small tilt is kept whole (`unit`: rotations and axes; translations and
// gravity get no +-1 beyond round-off); everything else loses only round-off. What changed beyond
// round-off goes into `report`.
template <int Rows, int Cols>
Eigen::Matrix<double, Rows, Cols> cleanGeometry(const Eigen::Matrix<double, Rows, Cols>& x,
                                                bool unit, GeometrySnap* report) {
  Eigen::Matrix<double, Rows, Cols> z =
      x.unaryExpr([](double v) { return std::abs(v) < kGeometrySnap ? 0.0 : roundOffClean(v); });
  if (unit)
    for (int i = 0; i < Rows; ++i)
      for (int j = 0; j < Cols; ++j) {
        if (std::abs(std::abs(z(i, j)) - 1.0) >= kGeometrySnap) continue;
        bool alone = true;
        for (int k = 0; k < Rows; ++k) alone = alone && (k == i || z(k, j) == 0.0);
        for (int k = 0; k < Cols; ++k) alone = alone && (k == j || z(i, k) == 0.0);
        if (alone) z(i, j) = z(i, j) > 0 ? 1.0 : -1.0;
      }
  if (report)
    for (int i = 0; i < Rows; ++i)
      for (int j = 0; j < Cols; ++j) {
        const double change = std::abs(z(i, j) - x(i, j));
        if (change <= GeometrySnap::kRoundOff) continue;
        ++report->count;
        report->largest = std::max(report->largest, change);
      }
  return z;
}

struct Rigid {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  bool identity() const { return R.isIdentity(0.0) && t.isZero(0.0); }
};

// The constant transform T with its rotation and translation cleaned (cleanGeometry).
Rigid rigid(const Eigen::Isometry3d& T, GeometrySnap* report);

struct JointStages {
  Rigid pre, post;
  JointType type = JointType::Revolute;
  Eigen::Vector3d u = Eigen::Vector3d::UnitZ();
  double offset = 0;  // revolute: the joint turns by q + offset
};

// Where the part of a joint's constant translations along its axis goes: it commutes with the
// joint motion (a rotation about, or a translation along, that axis), so it can sit in `pre`
// or in `post`. Which side is cheaper depends on the zeros and the products shared there.
enum class AxisShift : std::uint8_t { Keep, ToPre, ToPost };

// How a link's wrench is formed.
struct LinkForm {
  // 0: in the link frame. 1, 2, 3: in the joint frame before the joint motion (revolute
  // joints), with the inertia tensor carried through the joint rotation entry by entry (1),
  // keeping its trace (2), or split into a part the rotation leaves alone and a part turned by
  // twice the angle (3); see Builder::rotateParams.
  int frame = 0;
  // With frame > 0: the moment of the first moment, MS x a, taken in the axes after the joint
  // motion and turned with the rest of the wrench, instead of from the turned first moment.
  bool momentAfter = false;
  friend bool operator==(LinkForm a, LinkForm b) {
    return a.frame == b.frame && a.momentAfter == b.momentAfter;
  }
};

// The choices a generated recursion is built with, per joint.
struct Plan {
  std::vector<AxisShift> shift;
  std::vector<LinkForm> link;
};

// The stages of every joint. A DH/MDH angle offset theta is moved out of the constant
// transforms into the joint angle, so that right-angle twists keep their exact zeros.
std::vector<JointStages> jointStages(const Model& model, const std::vector<AxisShift>& shift,
                                     GeometrySnap* report = nullptr);

}  // namespace mindyn::codegen::internal
