// mindyn::Model -> pinocchio::Model, so that Pinocchio computes exactly the robot that mindyn and
// KDL compute (same geometry, same inertial parameters, same gravity), whatever the description
// the model came from (classic DH with `post` transforms, modified DH, URDF with merged links).
//
// mindyn writes the motion of joint k as T_{k-1,k}(q) = pre_k * J_k(q) * post_k. Pinocchio's
// joint frame k is put right after J_k(q), i.e. at link frame k * post_k^-1, so that
//   joint placement k = post_{k-1} * pre_k      (post_{-1} = identity: the base frame),
//   joint motion      = J_k(q) about / along `axis` in that frame,
//   body k            = the link's inertia, placed at post_k in the joint frame.
// For every link k a body frame named after the link sits at post_k in joint k's frame, and a
// frame "tool" at post_n * Model::tool, so link poses agree with mindyn's.
//
// Header-only; include it after the BOOST_MPL / BOOST_FUSION defines Pinocchio needs (see
// bench/CMakeLists.txt).
#pragma once

#include <cmath>
#include <pinocchio/multibody.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "mindyn/model.hpp"

namespace mindyn::bench {

/// Which Pinocchio joint models to use.
///  - Unaligned: JointModelRevoluteUnaligned / JointModelPrismaticUnaligned(axis) for every
///    joint (the generic translation);
///  - Specialized: JointModelRX/RY/RZ/PX/PY/PZ when the axis is exactly +x, +y or +z (what
///    Pinocchio's own URDF parser picks), the unaligned ones otherwise.
enum class PinocchioJoints { Unaligned, Specialized };

/// Pinocchio spatial inertia from ten classical parameters (XX XY XZ YY YZ ZZ MX MY MZ M, about
/// the link origin, link axes). A massless link keeps its rotational inertia; massless links
/// with first moments cannot be represented and throw mindyn::ModelError.
inline pinocchio::Inertia toPinocchioInertia(const Eigen::Ref<const Eigen::VectorXd>& p10,
                                             const std::string& link) {
  const double m = p10[9];
  const Eigen::Vector3d h = p10.segment<3>(6);
  const Eigen::Matrix3d I_origin = inertiaTensor(p10);
  if (m == 0.0) {
    if (!h.isZero(0.0))
      throw ModelError("link " + link +
                       ": zero mass with nonzero first moments cannot be given to Pinocchio");
    return pinocchio::Inertia(0.0, Eigen::Vector3d::Zero(), pinocchio::Symmetric3(I_origin));
  }
  const Eigen::Vector3d c = h / m;
  // Parallel-axis theorem: I_origin = I_com + m (|c|^2 1 - c c^T).
  const Eigen::Matrix3d I_com =
      I_origin - m * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
  return pinocchio::Inertia(m, c, pinocchio::Symmetric3(I_com));
}

inline pinocchio::SE3 toPinocchioSE3(const Eigen::Isometry3d& T) {
  return pinocchio::SE3(Eigen::Matrix3d(T.linear()), Eigen::Vector3d(T.translation()));
}

/// The joint model for one mindyn joint: revolute, prismatic, or a free-flyer or planar joint
/// (Pinocchio's JointModelFreeFlyer, JointModelPlanar: mindyn's q and v conventions are theirs).
inline pinocchio::JointModel toPinocchioJoint(const Joint& joint, PinocchioJoints joints) {
  if (joint.type == JointType::FreeFlyer)
    return pinocchio::JointModel(pinocchio::JointModelFreeFlyer());
  if (joint.type == JointType::Planar) return pinocchio::JointModel(pinocchio::JointModelPlanar());
  if (!joint.singleDof())
    throw ModelError(std::string("the benchmark's Pinocchio model takes no ") +
                     toString(joint.type) + " joint");
  const Eigen::Vector3d& a = joint.axis;
  const bool revolute = joint.type == JointType::Revolute;
  if (joints == PinocchioJoints::Specialized) {
    if (a == Eigen::Vector3d::UnitX())
      return revolute ? pinocchio::JointModel(pinocchio::JointModelRX())
                      : pinocchio::JointModel(pinocchio::JointModelPX());
    if (a == Eigen::Vector3d::UnitY())
      return revolute ? pinocchio::JointModel(pinocchio::JointModelRY())
                      : pinocchio::JointModel(pinocchio::JointModelPY());
    if (a == Eigen::Vector3d::UnitZ())
      return revolute ? pinocchio::JointModel(pinocchio::JointModelRZ())
                      : pinocchio::JointModel(pinocchio::JointModelPZ());
  }
  return revolute ? pinocchio::JointModel(pinocchio::JointModelRevoluteUnaligned(a))
                  : pinocchio::JointModel(pinocchio::JointModelPrismaticUnaligned(a));
}

/// The Pinocchio model of `model` with the inertial parameters `inertial` (10 n, classical, as
/// Model::inertial). Rotor inertia and friction are not part of it (Pinocchio's rnea ignores
/// them): compare with mindyn's default ParameterLayout.
inline pinocchio::Model toPinocchioModel(const Model& model, const Eigen::VectorXd& inertial,
                                         PinocchioJoints joints = PinocchioJoints::Unaligned) {
  model.validate();
  if (inertial.size() != 10 * model.nq())
    throw std::invalid_argument("inertial has " + std::to_string(inertial.size()) +
                                " entries, expected " + std::to_string(10 * model.nq()));
  pinocchio::Model pm;
  pm.name = model.name;
  pm.gravity = pinocchio::Motion(Eigen::Vector3d(model.gravity), Eigen::Vector3d::Zero());
  // per joint: its Pinocchio joint and body frame (a tree: each joint on its parent's)
  std::vector<pinocchio::JointIndex> ids;
  std::vector<int> body_frames;
  pinocchio::JointIndex parent = 0;
  Eigen::Isometry3d post_prev = Eigen::Isometry3d::Identity();
  int parent_frame = 0;  // "universe"
  for (int k = 0; k < model.nq(); ++k) {
    const Joint& j = model.joints[k];
    const int pk = model.parent(k);
    parent = pk < 0 ? 0 : ids[pk];
    post_prev = pk < 0 ? Eigen::Isometry3d::Identity() : model.joints[pk].post;
    parent_frame = pk < 0 ? 0 : body_frames[pk];
    const std::string& link = model.link_names[k + 1];
    const pinocchio::JointIndex id =
        pm.addJoint(parent, toPinocchioJoint(j, joints), toPinocchioSE3(post_prev * j.pre), j.name);
    const pinocchio::SE3 post = toPinocchioSE3(j.post);
    pm.appendBodyToJoint(id, toPinocchioInertia(inertial.segment<10>(10 * k), link), post);
    const int joint_frame = static_cast<int>(pm.addJointFrame(id, parent_frame));
    parent_frame = static_cast<int>(pm.addBodyFrame(link, id, post, joint_frame));
    ids.push_back(id);
    body_frames.push_back(parent_frame);
    parent = id;
    post_prev = j.post;
  }
  if (model.nq() > 0)
    pm.addFrame(pinocchio::Frame("tool", parent, static_cast<pinocchio::FrameIndex>(parent_frame),
                                 toPinocchioSE3(post_prev * model.tool), pinocchio::OP_FRAME),
                false);
  return pm;
}

inline pinocchio::Model toPinocchioModel(const Model& model,
                                         PinocchioJoints joints = PinocchioJoints::Unaligned) {
  return toPinocchioModel(model, model.inertial, joints);
}

}  // namespace mindyn::bench
