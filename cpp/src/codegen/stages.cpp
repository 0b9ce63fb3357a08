// The joint geometry of the generated recursion (see stages.hpp): round-off cleaning, the
// constant transforms of a joint and the stages of every joint.
#include "stages.hpp"

namespace mindyn::codegen::internal {

double roundOffClean(double x) {
  constexpr double tol = GeometrySnap::kRoundOff;
  if (std::abs(x) < tol) return 0.0;
  if (std::abs(x - 1.0) < tol) return 1.0;
  if (std::abs(x + 1.0) < tol) return -1.0;
  return x;
}

Rigid rigid(const Eigen::Isometry3d& T, GeometrySnap* report) {
  Rigid r;
  r.R = cleanGeometry<3, 3>(T.linear(), true, report);
  r.t = cleanGeometry<3, 1>(T.translation(), false, report);
  return r;
}

namespace {

Eigen::Isometry3d rotAbout(const Eigen::Vector3d& u, double angle) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle, u).toRotationMatrix();
  return T;
}

}  // namespace

std::vector<JointStages> jointStages(const Model& model, const std::vector<AxisShift>& shift,
                                     GeometrySnap* report) {
  std::vector<JointStages> out;
  const int n = model.nq();
  const bool dh = model.convention == "dh" && static_cast<int>(model.dh.size()) == n;
  const bool mdh = model.convention == "mdh" && static_cast<int>(model.dh.size()) == n;
  for (int k = 0; k < n; ++k) {
    const Joint& j = model.joints[k];
    JointStages s;
    s.type = j.type;
    s.u = cleanGeometry<3, 1>(j.axis, true, report);
    Eigen::Isometry3d pre = j.pre, post = j.post;
    const double theta = (dh || mdh) ? model.dh[k].theta : 0.0;
    if (j.type == JointType::Revolute && theta != 0.0) {
      // Rot(u, q) commutes with Rot(u, theta): dh has it in front of post, mdh at the end of
      // pre (where it also commutes with the translation along the axis).
      if (dh) post = rotAbout(j.axis, -theta) * post;
      if (mdh) pre = pre * rotAbout(j.axis, -theta);
      s.offset = theta;
    }
    const AxisShift sh = shift[k];
    if (sh != AxisShift::Keep) {
      // pre = T(t_pre) R_pre; post = T(t_post) R_post; u is in the joint frame.
      const Eigen::Vector3d u = j.axis.normalized();
      const double along = sh == AxisShift::ToPre
                               ? u.dot(post.translation())
                               : u.dot(pre.linear().transpose() * pre.translation());
      if (std::abs(along) >= kGeometrySnap) {
        Eigen::Isometry3d move = Eigen::Isometry3d::Identity();
        move.translation() = along * u;
        if (sh == AxisShift::ToPre) {
          pre = pre * move;
          post.translation() -= along * u;
        } else {
          pre = pre * move.inverse();
          post = move * post;
        }
      }
    }
    s.pre = rigid(pre, report);
    s.post = rigid(post, report);
    out.push_back(s);
  }
  return out;
}

}  // namespace mindyn::codegen::internal
