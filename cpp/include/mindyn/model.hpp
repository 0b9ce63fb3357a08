// The immutable description of a fixed-base manipulator, a serial chain or a tree: geometry, joint
// limits, drive data and the classical inertial parameters. Per-call workspaces live in
// mindyn::Data (data.hpp).
//
// Topology: joint k (0-based) moves link k+1 relative to the link carried by joint parent(k), or
// relative to the base (link 0) when parent(k) == -1. Joints are numbered so that a parent comes
// before its children (parent(k) < k). A serial chain has parent(k) = k - 1.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "mindyn/transmission.hpp"

namespace mindyn {

/// Raised for every description problem found while building or loading a model.
class ModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Raised when a file named by the user does not exist or cannot be read.
class FileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Largest magnitude accepted for any number of a robot description, in its SI unit (m, kg,
/// kg m^2, m/s^2, rad, N m, ...). Published URDFs write +-1e16 for "no position limit", so that is
/// the largest value still meaningful; a larger one is a mistake. The bound keeps results finite:
/// the dynamics multiply at most four description quantities in one term (mass x length^2 x
/// gravity, inertia x speed^2), below 1e64 for inputs within the bound, far from the double
/// overflow at 1.8e308, which leaves over 200 orders of magnitude for the joint state.
inline constexpr double kMaxDescriptionValue = 1e16;

/// Most joints a model may have. Per-call workspaces grow with n^2 (mass matrix) and a regressor
/// with 10 n^2 (80 MB at 1000 joints); no serial manipulator comes near it.
inline constexpr int kMaxModelJoints = 1000;

/// The kinematic pairs. Revolute and prismatic joints have one degree of freedom; the others are
/// the multi-degree-of-freedom pairs, which the multibody algorithms (multibody.hpp) take, and
/// base parameters by every method (the projection and recursive methods through
/// expandToSingleDof) and code generation of a floating or planar root (codegen/newton_euler.hpp).
/// Every other algorithm (the single-DOF dynamics of dynamics.hpp, KDL kinematics, IK, controller
/// steps) refuses a model with one (requireSingleDof) in one line naming the joint.
///
/// Configuration q (nq entries) and velocity v (nv entries) of each kind follow Pinocchio's
/// JointModel* convention, so that a state of Pinocchio is a state of mindyn unchanged. The
/// joint motion J(q) acts in the joint frame (after `pre`); v is the velocity of the frame moved
/// by J relative to the joint frame, expressed in the moved frame ("body" components):
///   Revolute     nq = nv = 1  q: angle about `axis`
///   Prismatic    nq = nv = 1  q: displacement along `axis`
///   Spherical    nq = 4, nv = 3  q: unit quaternion (x, y, z, w) of J's rotation about the
///                             origin; v: angular velocity (Pinocchio's JointModelSpherical)
///   Universal    nq = nv = 2  J = Rot(axis, q1) Rot(axis2, q2), axis2 in the frame after the
///                             first rotation (Pinocchio's JointModelUniversal)
///   Cylindrical  nq = nv = 2  q: (displacement along `axis`, angle about `axis`) (Pinocchio: a
///                             composite of a prismatic and a revolute joint on one axis)
///   Planar       nq = 4, nv = 3  q: (x, y, cos t, sin t), J = Trans(x, y, 0) Rot(z, t) in the
///                             joint frame's xy plane; v: (vx, vy, wz) (Pinocchio's
///                             JointModelPlanar)
///   FreeFlyer    nq = 7, nv = 6  q: (x, y, z, qx, qy, qz, qw), the position and unit
///                             quaternion of the moved frame; v: (linear; angular) velocity of
///                             the moved frame, both in its own axes, the linear one of its
///                             origin -- LINEAR FIRST, as Pinocchio's JointModelFreeFlyer (the
///                             spatial vectors inside mindyn are angular first)
/// The quaternions and (cos t, sin t) must have norm 1 (checkConfiguration); none is normalised.
/// q of a model is the joints' q one after the other, v the same (Model::configSize,
/// velocitySize; Pinocchio's nq and nv).
///
/// Written in a description: YAML `type:` revolute, continuous, prismatic, spherical,
/// universal, cylindrical, planar or floating (multi-DOF axes: the DH/MDH joint frame's z for
/// `axis`, its x for universal's `axis2`, its xy plane for planar); URDF `floating` (a
/// free-flyer) and `planar` (the plane normal to <axis>) joints, and a free-flyer or planar root
/// joint added above the root link on request (loadUrdf's `root_joint`). URDF has no spherical or
/// universal joint and the chains of revolute joints through massless links that stand for them
/// are kept as such (their dynamics are the same; their velocities are the joint rates).
enum class JointType { Revolute, Prismatic, Spherical, Universal, Cylindrical, Planar, FreeFlyer };

const char* toString(JointType type);

/// Configuration and velocity sizes of one joint of a kind (see JointType).
int configSize(JointType type);
int velocitySize(JointType type);

/// Limits of one joint; a value that the description does not give is NaN.
struct JointLimits {
  double lower = std::numeric_limits<double>::quiet_NaN();
  double upper = std::numeric_limits<double>::quiet_NaN();
  double velocity = std::numeric_limits<double>::quiet_NaN();
  double acceleration = std::numeric_limits<double>::quiet_NaN();
  double effort = std::numeric_limits<double>::quiet_NaN();
};

/// Drive data used to convert logged relative torques, tau = value * rated_torque * gear_ratio /
/// 1000, and logged motor currents, tau = current * torque_constant * gear_ratio.
struct Drive {
  double rated_torque = std::numeric_limits<double>::quiet_NaN();  // motor side [N m]
  double gear_ratio = std::numeric_limits<double>::quiet_NaN();
  double torque_constant = std::numeric_limits<double>::quiet_NaN();  // motor side [N m / A]
};

/// One row of a Denavit-Hartenberg table, kept for display. For `dh`: a, alpha, d, theta.
/// For `mdh` (Khalil-Kleinfinger): alpha_j, d_j, theta_j, r_j stored as alpha, a (= d_j), theta, d
/// (= r_j).
struct DHRow {
  double a = 0, alpha = 0, d = 0, theta = 0;
};

/// Joint k moves link k relative to its parent link (link k-1 in a chain):
///   T_{parent,k}(q) = pre * J(q) * post,
/// J(q) a rotation by q about `axis` (revolute) or a translation by q along `axis` (prismatic),
/// `axis` a unit vector in the joint frame through its origin. URDF and modified DH give post = I;
/// classic DH gives pre = I and puts the fixed part of the row into post.
struct Joint {
  std::string name;
  JointType type = JointType::Revolute;
  Eigen::Isometry3d pre = Eigen::Isometry3d::Identity();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d axis2 = Eigen::Vector3d::UnitX();  // universal joints' second axis
  Eigen::Isometry3d post = Eigen::Isometry3d::Identity();
  JointLimits limits;
  Drive drive;

  int nq() const { return configSize(type); }
  int nv() const { return velocitySize(type); }
  bool singleDof() const { return type == JointType::Revolute || type == JointType::Prismatic; }

  /// Homogeneous transform T_{parent,k}(q) of a single-DOF joint.
  Eigen::Isometry3d transform(double q) const;
  /// The same for any kind, from the joint's nq() configuration entries.
  Eigen::Isometry3d transform(const double* q) const;
};

/// Names of the ten classical inertial parameters of one link, in storage order.
inline constexpr const char* kInertialNames[10] = {"XX", "XY", "XZ", "YY", "YZ",
                                                   "ZZ", "MX", "MY", "MZ", "M"};

/// Which optional per-joint parameters a classical parameter vector holds, and where.
/// The vector is link by link, then one block over the joints:
///   [XX1..M1, (Ia1), (Fv1, Fc1, (F31)), XX2, ..., (Off1, ..., Offn)].
/// Slot k's rotor inertia and friction act on joint k, or on motor k when the model's
/// `motorSide()` (then with the motor velocity v = T_k dq in place of dq_k below).
///
/// Terms of a joint's torque that belong to no link and no motor (the torque offset Off_k) form
/// the block after the last link: they keep their place and their meaning whatever the other
/// terms, the order of the link blocks or the drive side (an offset adds to joint k's torque
/// even when rotor inertia and friction act on the motors). A further per-joint term joins that
/// block here (a flag, its index, its name in parameterNames, its column in the regressors of
/// dynamics.hpp) and nowhere else.
struct ParameterLayout {
  bool rotor = false;     // Ia_k: tau_k += Ia_k * ddq_k
  bool friction = false;  // Fv_k, Fc_k (, F3_k): tau_k += Fv_k v + friction shapes (FrictionModel)
  int friction_columns = 2;  // 2, or 3 for the friction models with a third parameter
  /// Off_k: tau_k += Off_k, a constant joint torque (a joint's, never a motor's). Its column is
  /// e_k in the inverse-dynamics regressor and in -dL/dq of the momentum regressors (beta of a
  /// momentum observer), and q_k in the potential-energy regressor (the offset's work: the
  /// energy model's column over a window is q_k(t1) - q_k(t0)).
  bool offset = false;

  int perLink() const { return 10 + (rotor ? 1 : 0) + (friction ? friction_columns : 0); }
  /// Entries of the link blocks (the classical vector without the joint block).
  int linkSize(int n) const { return n * perLink(); }
  int size(int n) const { return linkSize(n) + (offset ? n : 0); }
  int rotorIndex(int k) const { return k * perLink() + 10; }
  int viscousIndex(int k) const { return k * perLink() + 10 + (rotor ? 1 : 0); }
  int coulombIndex(int k) const { return viscousIndex(k) + 1; }
  /// The third friction parameter (Fa of Asymmetric, Fs of Stribeck); only when
  /// friction_columns == 3.
  int thirdFrictionIndex(int k) const { return viscousIndex(k) + 2; }
  /// Friction column i (0: Fv, 1: Fc, 2: the third) of slot k.
  int frictionIndex(int k, int i) const { return viscousIndex(k) + i; }
  /// Joint k's torque offset, of n joints; only when `offset`.
  int offsetIndex(int n, int k) const { return linkSize(n) + k; }
  /// The same layout without the joint block (what the link-by-link algorithms take).
  ParameterLayout links() const {
    ParameterLayout l = *this;
    l.offset = false;
    return l;
  }
  /// The layout whose size for n joints is `size` with `friction_columns` friction columns
  /// and no offsets (Model::layoutOfSize gives the model's), or throws ModelError. Offsets are
  /// never inferred from a size: 11 n is rotor inertia, not offsets.
  static ParameterLayout fromSize(int n, long size, int friction_columns = 2);
};

/// The prefix of the torque offsets' names: the one place it is spelled (the bindings give it
/// to Python as OFFSET_PREFIX).
inline constexpr const char kOffsetPrefix[] = "Off";
/// The name of joint k's (0-based) torque offset: "Off1" for k = 0.
std::string offsetName(int k);

/// The friction model of every slot (joint, or motor when the model's `motorSide()`), with v the
/// slot's velocity [rad/s | m/s] and w_k its velocity scale (`FrictionModel::velocity`):
///   Coulomb     Fv v + Fc sign(v)                                   (2 columns, the default)
///   Asymmetric  Fv v + Fc sign(v) + Fa |sign(v)|                    (3: Coulomb torque Fc + Fa
///                                                                    moving forward, Fc - Fa
///                                                                    backward)
///   Smooth      Fv v + Fc tanh(v / w_k)                             (2: width w_k)
///   Stribeck    Fv v + Fc sign(v) + Fs sign(v) exp(-(v / w_k)^2)    (3: Stribeck velocity w_k)
/// sign(0) = 0.
enum class FrictionKind { Coulomb, Asymmetric, Smooth, Stribeck };

struct FrictionModel {
  FrictionKind kind = FrictionKind::Coulomb;
  Eigen::VectorXd velocity;  // n, w_k > 0 for Smooth and Stribeck; empty otherwise
  int columns() const {
    return kind == FrictionKind::Asymmetric || kind == FrictionKind::Stribeck ? 3 : 2;
  }
  /// True for the kinds with a velocity scale (Smooth, Stribeck).
  bool scaled() const { return kind == FrictionKind::Smooth || kind == FrictionKind::Stribeck; }
  /// Throws ModelError (one line) unless `velocity` has n positive finite entries (at most
  /// kMaxDescriptionValue) for a scaled kind and none otherwise.
  void validate(int n) const;
};

/// "coulomb", "asymmetric", "smooth" or "stribeck".
const char* toString(FrictionKind kind);
/// The kind of a name of toString, or throws ModelError naming the four.
FrictionKind frictionKindOf(const std::string& name);

struct Model {
  std::string name;
  std::string source;               // file it came from, or "bundled:<name>" / "generated"
  std::string convention = "urdf";  // urdf | dh | mdh | generated
  std::vector<Joint> joints;
  std::vector<std::string> link_names;  // n + 1 names: base, then each moving link
  /// Parent joint of each joint, -1 for the base; empty for a serial chain (parent(k) = k - 1).
  /// When given: n entries with -1 <= parents[k] < k.
  std::vector<int> parents;
  std::vector<DHRow> dh;           // empty unless loaded from a DH/MDH table
  bool synthetic_inertia = false;  // inertial values invented, not measured/published
  std::string notes;

  Eigen::Vector3d gravity{0.0, 0.0, -9.81};
  Eigen::Isometry3d tool = Eigen::Isometry3d::Identity();  // last link (n) frame -> tool frame

  Eigen::VectorXd inertial;       // 10 n classical inertial parameters about link origins
  Eigen::VectorXd rotor_inertia;  // n, joint side (as descriptions give them; see parameters())
  Eigen::VectorXd viscous;        // n, joint side
  Eigen::VectorXd coulomb;        // n, joint side
  /// n, the third friction parameter of the friction model (Fa of Asymmetric, Fs of
  /// Stribeck), joint side; empty reads as zero.
  Eigen::VectorXd third_friction;
  /// n constant torque offsets (Off1 .. Offn, a joint-terms file gives them; a description
  /// gives none), or empty: zero. parameters() puts them in a layout's offset entries.
  Eigen::VectorXd torque_offset;
  /// Motors and their coupling to the joints (transmission.hpp); empty when the description
  /// declares none (each joint driven directly).
  Transmission transmission;
  /// URDF transmissions of types not read (none of the three of ros_control's
  /// transmission_interface): name, type as written, the joints they name, line. Their joints
  /// are modelled as driven directly.
  std::vector<TransmissionGroup> unread_transmissions;
  /// Where the layout's rotor inertia and friction act when the model has transmissions: on
  /// the motors (true, the default; slot k of Ia/Fv/Fc belongs to motor k, in motor units:
  /// tau += T^T (Ia T ddq + Fv T dq + Fc sign(T dq))) or on the joints (false; as without
  /// transmissions). A transmission of more motors than joints has no slot per motor: its
  /// terms act on the joints whatever this says (motorSide()).
  bool drive_terms_on_motors = true;
  /// The shape of the friction terms (Coulomb unless a friction model is chosen).
  FrictionModel friction_model;

  /// True when rotor inertia and friction act through the transmission (see above): declared
  /// transmissions of one motor per joint, and drive_terms_on_motors.
  bool motorSide() const {
    return !transmission.empty() && drive_terms_on_motors && transmission.nm() == nq();
  }

  /// Number of joints (and of moving links). The name is historical: it is the size of q only
  /// when every joint is revolute or prismatic (singleDof()); configSize() and velocitySize()
  /// are the sizes of q and v in general (Pinocchio's nq and nv).
  int nq() const { return static_cast<int>(joints.size()); }
  int configSize() const;
  int velocitySize() const;
  /// True when every joint is revolute or prismatic.
  bool singleDof() const;
  /// Index of the joint that carries joint k's parent link, -1 for the base.
  int parent(int k) const { return parents.empty() ? k - 1 : parents[static_cast<size_t>(k)]; }
  /// True when every joint's parent is the joint before it (a serial chain).
  bool isSerial() const;
  /// True when joint j supports joint k: j == k or j is an ancestor of k.
  bool supports(int j, int k) const;

  /// The layout with or without rotor inertia and friction, its friction columns those of
  /// `friction_model` (the one place a layout is formed from these two choices).
  ParameterLayout layout(bool rotor, bool friction, bool offset = false) const {
    ParameterLayout l{rotor, friction};
    l.friction_columns = friction_model.columns();
    l.offset = offset;
    return l;
  }
  /// The layout of a parameter vector of `size` entries (10, 11, 10 + c or 11 + c per joint,
  /// c the friction model's columns), or throws ModelError.
  ParameterLayout layoutOfSize(long size) const {
    return ParameterLayout::fromSize(nq(), size, friction_model.columns());
  }

  /// Classical parameter names for a layout, e.g. XX1, ..., M1, Ia1, Fv1, Fc1, XX2, ...
  /// (the third friction column Fa_k for Asymmetric, Fs_k for Stribeck), then Off1, ..., Offn
  std::vector<std::string> parameterNames(ParameterLayout layout = {}) const;
  /// Classical parameter values of this model in a layout. On the motor side (motorSide()),
  /// slot k holds motor k's values: its own (transmission.rotor_inertia, viscous, coulomb,
  /// third_friction) where given, otherwise derived from the joint-side rotor_inertia, viscous,
  /// coulomb and third_friction: those of its joint divided by r^2, r^2, |r| and r (Fa) or |r|
  /// (Fs) for a motor that alone drives one joint alone with ratio r, 0 for a motor that turns
  /// with several joints. Offsets are
  /// torque_offset's (0 when empty: a description gives none).
  Eigen::VectorXd parameters(ParameterLayout layout = {}) const;

  /// Checks sizes, finiteness, magnitudes, unit axes and rigid transforms; throws ModelError
  /// naming the problem. Loaders check each input against kMaxDescriptionValue; a model built
  /// from them folds up to 100 inputs into one value (fixed joints into one origin, rigidly
  /// attached links into one body), so here lengths and masses may reach 100x that bound, first
  /// moments its square and second moments its cube; limits, gravity, rotor inertia and friction
  /// are taken as given and keep the bound itself.
  void validate() const;
};

/// Throws ModelError "<what> takes revolute and prismatic joints only; model '<name>' has the
/// <kind> joint '<joint>' (...)" unless model.singleDof().
void requireSingleDof(const Model& model, const std::string& what);

/// A model with the same real links whose multi-DOF joints are each replaced by a chain of
/// single-DOF joints through massless intermediate links, with the same motion of every real
/// link (docs/base-parameters.md, "Joints of several degrees of freedom"): in the joint frame
/// (after `pre`),
///   Spherical    revolute about z, y, x (J = Rz Ry Rx, the Z-Y-X angles of the rotation)
///   Universal    revolute about `axis`, then about `axis2`
///   Cylindrical  prismatic along `axis`, then revolute about `axis`
///   Planar       prismatic along x, along y, then revolute about z
///   FreeFlyer    prismatic along x, y, z, then revolute about z, y, x
/// The first joint of a chain keeps `pre`, the last `post` and the real link's inertia; the
/// others have identity frames and no inertia. The charts are singular on a set of measure zero
/// (Z-Y-X angles at +-pi/2 of the middle one), elsewhere each real link has the same velocities
/// and accelerations as with the pair, so the regressor and energies of the real links span the
/// same functions. Only the link inertia is kept: no rotor inertia, friction, transmission or
/// limits on the added joints. A model of revolute and prismatic joints comes back unchanged.
/// With `keep_free_flyer_roots`, a free-flyer joint whose parent is the world stays as it is
/// (the projection method takes a floating base natively: docs/base-parameters.md).
/// Throws ModelError for a model that Model::validate refuses.
struct SingleDofExpansion {
  Model model;
  /// Per joint of `model`: the joint of the original model whose link it moves (its last
  /// factor), or -1 for a massless intermediate link.
  std::vector<int> link;
  /// The columns of the classical link parameters (10 per link) of the original model in those
  /// of `model`: original column c is column column[c].
  std::vector<int> column;
};
SingleDofExpansion expandToSingleDof(const Model& model, bool keep_free_flyer_roots = false);

/// Throws std::invalid_argument naming the joint unless every quaternion and planar (cos, sin)
/// pair of the configuration q (model.configSize() entries, checked) has norm 1 within 1e-6.
void checkConfiguration(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q);

/// Ten classical parameters about the link origin from mass, centre of mass and the inertia
/// tensor about the COM, all in the same (link) axes.
Eigen::Matrix<double, 10, 1> inertialFromCom(double mass, const Eigen::Vector3d& com,
                                             const Eigen::Matrix3d& inertia_com);

/// The same when the inertia is given in a frame rotated by R relative to the link axes
/// (URDF <inertial><origin rpy>): I_link = R I R^T.
Eigen::Matrix<double, 10, 1> inertialFromUrdf(double mass, const Eigen::Vector3d& com,
                                              const Eigen::Matrix3d& R,
                                              const Eigen::Matrix3d& inertia_com);

/// Inertia tensor about the link origin from a 10-vector.
Eigen::Matrix3d inertiaTensor(const Eigen::Ref<const Eigen::VectorXd>& p10);

/// Throws ModelError "<source>:<line>: not UTF-8 text (byte 0x.. at offset N)" unless `text` is
/// valid UTF-8 (the encoding of URDF and YAML files, and what names must be to reach Python).
void requireUtf8(const std::string& text, const std::string& source);

/// `text` with control characters and bytes that are not UTF-8 written as escapes (\n, \t, \r,
/// \xNN), so that a message quoting a file stays on one line and reaches Python intact.
std::string escapeControl(const std::string& text);

/// Pinocchio's dynamic-parameter order per body: m, mcx, mcy, mcz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz.
Eigen::VectorXd toPinocchioOrder(const Eigen::Ref<const Eigen::VectorXd>& inertial);
Eigen::VectorXd fromPinocchioOrder(const Eigen::Ref<const Eigen::VectorXd>& pinocchio);

}  // namespace mindyn
