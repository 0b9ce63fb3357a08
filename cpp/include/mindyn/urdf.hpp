// Loading a fixed-base model from a URDF description (parsed with urdfdom): the whole tree, or the
// serial chain from the root link to a tip link.
//
// Links before the first moving joint form the fixed base and their inertia is ignored. Every
// other link that is not the child of a moving joint of the model is rigidly attached to a link of
// the model and merged into it, so the moving mass of the URDF is preserved:
//  - fixed joints between moving ones fold their origin into the next moving joint's `pre`;
//    in a chain, fixed joints after the last moving joint (tip given past it, e.g. "tool0")
//    become `Model::tool`;
//  - fixed children that hang off the model's links (sensor frames, hands, flanges) are merged;
//  - in a chain, moving joints that leave it (e.g. gripper fingers when tip = the hand) are locked
//    at q = 0 clamped into their limits and merged too; `Model::notes` names them.
//
// Without a tip the whole URDF is loaded: a chain if it has one moving leaf, else a tree with
// `Model::parents` set, its joints numbered depth-first from the root, the children of a link in
// the order of their joint names (urdfdom's order, which Pinocchio's URDF parser follows too, so
// that joint k is Pinocchio's joint k + 1). A tree's tool frame is the identity (on the last
// link). Floating and planar joints become free-flyer and planar joints (model.hpp, JointType;
// a planar joint moves in the plane normal to its <axis>). With `root_joint` "floating" or
// "planar" a joint of that kind named "root_joint" is put between a base link "world" and the
// root link, which becomes the first moving body with every link rigidly attached to it (the
// floating base, as Pinocchio's buildModel with a JointModelFreeFlyer or JointModelPlanar root);
// the whole URDF is then a tree even with one leaf. A mimic joint has no place in the model
// (its coupling to another joint): it is refused on a chain given by a tip, and without a tip it
// is locked at q = 0 clamped into its limits and merged like a joint off the chain (grippers'
// mirrored fingers), unless moving joints hang below it (refused).
//
// The file must be UTF-8 and its links a tree: a joint whose parent is its child, a link entered
// by two joints or a loop of joints is refused by name. Every number of a link's <inertial> and of
// a joint's <origin>, <axis>, <limit>, <dynamics>, <mimic>, <safety_controller> and <calibration>
// is read from the XML before urdfdom reads it (which logs a number it cannot read and keeps the
// link with mass and inertia 0, or takes a misspelt attribute as absent): a number that cannot
// be read ("3.7.0", "3,7", "abc", ""), is not finite, exceeds kMaxDescriptionValue in magnitude,
// a negative mass or limit, a missing <mass>, <inertia> or attribute, an attribute or element
// that URDF does not define there (in <inertial>, <origin>, <mass>, <inertia>, <axis>) or that
// looks like a misspelling of one it does (ixxx, lowr, <inertal>), and a second <inertial>,
// <origin>, <axis>, <limit>... are refused in one line naming the file, line, link or joint,
// element, attribute and value. White space around and between numbers is allowed (XML Schema's
// xs:double collapses it) and read, not taken as 0. A link without <inertial> is massless; the
// notes name those merged into the model.
//
// ros_control <transmission> elements (ROS 1 form in <robot>, ROS 2 form in <ros2_control>) of
// types SimpleTransmission, DifferentialTransmission and FourBarLinkageTransmission, and PR2's
// older ones (pr2_mechanism_model's SimpleTransmission and WristTransmission, in <robot>), become
// `Model::transmission` (transmission.hpp); a joint of the model that none drives is driven
// directly, a joint locked in the model adds a constant to its motors, other types are left
// out; the notes say which.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

#include "mindyn/model.hpp"

namespace mindyn {

/// Loads the chain root -> `tip` of the URDF file `path`; an empty `tip` loads the whole URDF
/// (a chain or a tree, see above). Throws FileError if the file is missing or unreadable,
/// ModelError for any description problem.
Model loadUrdf(const std::string& path, const std::string& tip = "",
               const std::string& root_joint = "");

/// The same from URDF text; `source` names it in error messages and in `Model::source`.
Model parseUrdf(const std::string& xml, const std::string& tip = "",
                const std::string& source = "string", const std::string& root_joint = "");

/// Moves ten classical parameters (XX XY XZ YY YZ ZZ MX MY MZ M, about the child origin in child
/// axes) to the parent frame, `parent_T_child` mapping child coordinates to parent coordinates:
///   h' = R h + m p,  I' = R I R^T - [p]x [R h]x - [R h]x [p]x - m [p]x [p]x.
Eigen::Matrix<double, 10, 1> transformInertial(const Eigen::Matrix<double, 10, 1>& inertial,
                                               const Eigen::Isometry3d& parent_T_child);

}  // namespace mindyn
