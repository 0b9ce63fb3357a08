// Transmissions between motors and joints, as data of the model. Their dynamics -- rotor inertia
// and friction of the motors, acting through T -- are those of the layout's rotor and friction
// slots when the model's `motorSide()` (model.hpp; computed in cpp/src/drive_terms.hpp).
//
// Conventions (SI units; positions in rad or m as the joint/motor is revolute or prismatic):
//   motor positions   q_m = T q + c        T (n_m x n): gear ratios and coupling terms,
//                                          c (n_m): motor offsets (motor position at q = 0)
//   motor velocities  dq_m = T dq
//   joint torques     tau = T^T tau_m      (virtual work: tau_m . dq_m = tau . dq)
// Row i of T belongs to motor i (`motors[i]`), column k to joint k of the model. A model without
// transmissions has T empty (n_m = 0): each joint is driven directly, as before. A joint of
// several degrees of freedom (a floating or planar base, Joint::singleDof() false) is driven by
// no motor: one column cannot describe it, and its column of T is zero.
//
// ros_control's types (transmission_interface), with actuator reductions a_i, joint reductions
// j_k (1 unless given) and joint offsets o_k (0 unless given), x_k = q_k - o_k:
//   SimpleTransmission             q_m1 = a_1 x_1                       (ROS 1: the reduction of
//                                                                        <actuator>; ROS 2: of
//                                                                        <joint>)
//   DifferentialTransmission       q_m1 = a_1 (j_1 x_1 + j_2 x_2)
//                                  q_m2 = a_2 (j_1 x_1 - j_2 x_2)
//   FourBarLinkageTransmission     q_m1 = a_1 j_1 x_1
//                                  q_m2 = a_2 (x_1 + j_2 x_2)          (motor 2 turns with both)
// The joint torques follow from T by virtual work. For the differential that is ros_control's
// own effort map; for the four-bar linkage ros_control's effort map is not the transpose of its
// position map, and T^T (consistent with the positions) is used here.
//
// PR2's older types (pr2_mechanism_model), x_k = q_k (its joints' reference positions are set
// by the calibration at run time, not by the description: no motor offsets):
//   pr2_mechanism_model/SimpleTransmission    q_m1 = a_1 x_1     (a_1: <mechanicalReduction>
//                                                                 of <transmission>)
//   pr2_mechanism_model/WristTransmission     q_right = a_r ( j_f x_flex - j_r x_roll)
//                                             q_left  = a_l (-j_f x_flex - j_r x_roll)
// (actuators: right, left; joints: flex, roll; each reduction the mechanicalReduction attribute
// of its element). pr2_mechanism_model's effort maps are T^T of these. The wrist is ros_control's
// DifferentialTransmission with actuator reductions a_r, -a_l and joint reductions j_f, -j_r.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace mindyn {

struct Joint;  // model.hpp

/// PR2's transmission types read (pr2_mechanism_model), as TransmissionGroup::type.
inline constexpr const char* kPr2Simple = "pr2_mechanism_model/SimpleTransmission";
inline constexpr const char* kPr2Wrist = "pr2_mechanism_model/WristTransmission";

/// One transmission as the description declares it, kept to show and to write it back.
struct TransmissionGroup {
  std::string name;
  /// SimpleTransmission | DifferentialTransmission | FourBarLinkageTransmission (ros_control's
  /// transmission_interface types) | kPr2Simple | kPr2Wrist (PR2's).
  std::string type;
  std::vector<std::string> joints;     // by role: joint1, joint2 (PR2's wrist: flex, roll)
  std::vector<std::string> actuators;  // by role: actuator1, actuator2 (PR2's wrist: right, left)
  std::vector<double> actuator_reduction;
  std::vector<double> joint_reduction;
  std::vector<double> joint_offset;
  int line = 0;  // where it is declared (0: unknown)

  /// The part of T it declares: rows for `actuators`, columns for `joints`.
  Eigen::MatrixXd matrix() const;
  /// Motor position of each actuator at q = 0 from the joint offsets: -matrix() * offsets.
  Eigen::VectorXd offsets() const;
};

struct Transmission {
  std::string format;                     // "" (none), "ros1", "ros2" (URDF forms) or "yaml"
  Eigen::MatrixXd T;                      // n_m x n
  Eigen::VectorXd offset;                 // n_m: c of q_m = T q + c
  std::vector<std::string> motors;        // n_m unique names
  std::vector<std::string> types;         // n_m: its transmission's type, "direct" for a joint
                                          // without one, "matrix" from YAML rows
  Eigen::VectorXd torque_constant;        // n_m [N m/A], NaN where the description gives none
  std::vector<TransmissionGroup> groups;  // as declared in a URDF (empty from YAML)
  /// Motor-side rotor inertia [kg m^2] and viscous [N m s/rad] and Coulomb [N m] friction of
  /// each motor as a YAML description gives them: n_m entries (NaN for a motor without), or
  /// empty when it gives none. Model::parameters puts them in the motor slots.
  Eigen::VectorXd rotor_inertia, viscous, coulomb;
  /// The friction model's third parameter of each motor (Fa [N m] of the asymmetric model, of
  /// either sign; Fs [N m] of the Stribeck model), as a joint-terms file gives it for a motor
  /// that turns with several joints: n_m entries (NaN for a motor without), or empty.
  Eigen::VectorXd third_friction;

  bool empty() const { return motors.empty(); }
  int nm() const { return static_cast<int>(motors.size()); }
  /// The joint that motor k alone drives and drives alone (soleJoint of T), or -1.
  int soleJoint(int k) const noexcept;

  /// Checks sizes against the model's `joints`, finiteness and magnitude of every entry,
  /// unique motor names, that every single-DOF joint is driven (a non-zero column) and no
  /// multi-DOF joint is (a zero column), and that the single-DOF joints' columns of T have full
  /// column rank (so that tau = T^T tau_m reaches their torques and q_m determines them);
  /// throws ModelError naming the motor, joint or the rank found.
  void validate(const std::vector<Joint>& joints, const std::string& who) const;
};

/// The joint j that motor k of the transmission T (n_m x n) alone drives and drives alone (row k
/// of T is r e_j and column j is r e_k), or -1 (motor k turns with several joints, or another
/// motor turns joint j too). Such a motor's rotor inertia and friction act on joint j as
/// r^2 Ia, r^2 Fv, |r| Fc, |r| Fs and r Fa: the only motors whose terms a joint can carry (the
/// others' are the motor's own, Transmission's rotor_inertia ... third_friction). The one place
/// this is decided.
int soleJoint(const Eigen::MatrixXd& T, int k) noexcept;

/// The transmission of a model from the declared groups. `joints` are the model's joints;
/// a group's joint that is not one of them but is a joint of the description locked at a
/// position (`locked_names`, `locked_q`: fixed joints and joints off the loaded chain) adds the
/// constant T_k q_k to its motors; a group with no joint of the model is dropped, as is one
/// naming no joint of the description at all (noted; one naming some is refused). When some
/// groups remain, a single-DOF joint of the model that none drives gets a direct drive (a motor
/// named after it, type "direct", ratio 1); a multi-DOF joint gets no motor (a zero column).
/// `notes` receives a sentence on each of these. Throws ModelError (prefixed by `source`) for a
/// joint driven twice, an unknown joint name or a group naming a multi-DOF joint of the model.
Transmission assembleTransmission(const std::vector<TransmissionGroup>& groups,
                                  const std::string& format, const std::vector<Joint>& joints,
                                  const std::vector<std::string>& locked_names,
                                  const std::vector<double>& locked_q, const std::string& source,
                                  std::string* notes);

}  // namespace mindyn
