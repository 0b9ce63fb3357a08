// The Newton-Euler recursion of a model written into an expression graph, customised to the
// model: the constant joint transforms enter with their exact zeros and ones, the parameters
// with their exact zeros (for base parameters every non-base classical entry is zero), and each
// link's wrench is formed as a linear form in its parameters whose coefficients are shared
// kinematic products. What does not reach an output is never scheduled.
//
// Frames: every joint is split into stages: the constant transform `pre`, the joint motion
// about/along the axis through the stage origin, the constant transform `post`; link k's
// wrench is added in link frame k. Forward: angular velocity and acceleration and the linear
// acceleration of each stage origin (gravity as an upward base acceleration). Backward: the
// wrench (moment about the stage origin, force); the torque is the axis component of the moment
// (revolute) or the force (prismatic) right after the joint motion. The part of a constant
// translation that lies along a joint's axis commutes with the joint motion and is placed in
// `pre` or `post`, joint by joint, wherever the generated function has fewer operations.
//
// A link's wrench may instead be formed in the joint frame before the joint motion (revolute
// joints), with the link's parameters turned by the joint angle: the link's angular velocity
// there is the parent's plus the joint rate along a fixed axis, so that no rotation of the
// velocities into the link frame or of the wrench out of it is needed, two of the kinematic sums
// are the parent's, and a link after a joint whose parent turns about one fixed axis (the second
// link of most arms) sees sparse velocities. The wrench is carried as linear forms in the
// parameters through sums and signed permutations, so that equal kinematic coefficients of
// different links share one product. Which frame each link uses is chosen by operation count.
//
// A floating base (checkCodegenJoints): a free-flyer or planar joint on the fixed base, revolute
// and prismatic joints below; q, dq and ddq in Pinocchio's convention (model.hpp), the
// inertial parameters only, and the inverse dynamics optionally with contact wrenches (Contacts).
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "mindyn/base_parameters.hpp"
#include "mindyn/codegen/expr.hpp"
#include "mindyn/model.hpp"

namespace mindyn::codegen {

enum class Function {
  InverseDynamics,
  Gravity,
  Regressor,
  SlotineLi,  ///< the products of the Slotine-Li regressor a controller step needs
};

/// "inverse_dynamics", "gravity", "regressor" or "slotine_li" (the suffix of the generated
/// function names).
const char* toString(Function f);

/// The parameter vector `p` a generated function takes, and how it maps to the classical
/// parameters: pi = E p.
struct ParameterSet {
  ParameterLayout layout;  // of the link blocks (without offsets: those are `offsets`)
  bool base = true;
  std::vector<std::string> names;
  std::vector<std::string> formulas;  // base: "XXR2 = XX2 - YY2 + ..."; classical: empty
  Eigen::VectorXd values;             // the model's values (p = Y pi for a base set)
  Eigen::MatrixXd E;                  // layout.size(n) x names.size()
  /// 0, or n: the last n entries of p are constant torque offsets Off1..OffN, tau_k += Off_k in
  /// the inverse dynamics and the regressor (column 1 in joint k's row), not in the gravity
  /// torque; their columns of E are zero (no classical parameter).
  int offsets = 0;
  int size() const { return static_cast<int>(names.size()); }
};

/// Throws ModelError unless code can be generated for the model's joints: revolute and prismatic
/// joints, and free-flyer or planar joints on the fixed base (a floating base: its q, dq and ddq
/// in Pinocchio's convention, model.hpp), which take the inertial parameters only (`layout`
/// without rotor inertia, friction or torque offsets). The message names the joint.
void checkCodegenJoints(const Model& model, ParameterLayout layout);

/// The equations-of-motion base set of `bp`: pi = embed(p_b); with the torque offsets of its
/// layout as the last n entries.
ParameterSet baseParameterSet(const Model& model, const BaseParameters& bp);
/// All classical parameters of a layout (E = identity; its offsets the last n entries).
ParameterSet classicalParameterSet(const Model& model, ParameterLayout layout);
/// The set with a torque offset per joint appended (names Off1..OffN, values 0, formulas
/// "Offk = Offk" for a base set). Throws ModelError when it has offsets already.
ParameterSet withOffsets(const Model& model, ParameterSet set);

/// Constants of the geometry (joint transforms and axes, gravity) within this of 0 are taken as
/// exactly 0 in the generated recursion, and an entry of a rotation or an axis within this of
/// +-1 as +-1 when the rest of its row and column is 0, so that their products vanish or are
/// free: beyond round-off this affects descriptions written with a truncated pi/2, such as the
/// rpy 1.57079632679 of many URDF files (cos = 4.9e-12). A small tilt (an axis 3e-5 off a
/// coordinate axis) is kept whole. GeometrySnap reports what changed.
inline constexpr double kGeometrySnap = 1e-9;

/// The constants kGeometrySnap changed by more than round-off (kRoundOff), and the largest change.
struct GeometrySnap {
  static constexpr double kRoundOff = 1e-14;
  int count = 0;
  double largest = 0.0;
  /// Over several functions of one model: the most constants changed, the largest change.
  void include(const GeometrySnap& other) {
    count = count > other.count ? count : other.count;
    largest = largest > other.largest ? largest : other.largest;
  }
};

/// The contact wrenches a floating-base inverse dynamics takes (the input f, 6 per contact):
/// link `links[c]` (the link joint links[c] moves) receives f[6 c .. 6 c + 5], the force and then
/// the moment about the link's origin, in world axes (`world`, Pinocchio's LOCAL_WORLD_ALIGNED)
/// or in the link's own axes; the function gives tau = rnea(q, dq, ddq) - sum_c J_c^T f_c.
struct Contacts {
  std::vector<int> links;
  bool world = true;
};

/// One generated function.
struct GeneratedFunction {
  Function function = Function::InverseDynamics;
  int n = 0;             // joints (velocity coordinates: the size of tau)
  int np = 0;            // parameters
  int contacts = 0;      // contact wrenches (inverse dynamics of a floating base)
  bool numeric = false;  // parameter values baked in (inverse dynamics and gravity only)
  Graph graph;
  /// tau (n entries) or the regressor, row-major n x np.
  std::vector<Ref> outputs;
  Program program;
  GeometrySnap snap;  // of the chosen formulation
};

/// What the choice among the exact formulations minimises: multiplications plus additions
/// (ties: fewer additions), or additions first (ties: fewer multiplications).
enum class Objective { Operations, Additions };

/// "operations" or "additions".
const char* toString(Objective o);

/// Builds one function. `values` (size np) are baked in when `numeric` (ignored for the
/// regressor, which does not depend on the parameters). Throws ModelError on a size mismatch.
/// Joint by joint, the recursion chooses where the along-axis translation goes and in which
/// frame the link's wrench is formed (its own, or the joint frame before the joint motion with
/// the parameters turned by the joint angle), keeping what lowers the count by `objective`.
/// `contacts` (inverse dynamics only) subtract the generalised forces of contact wrenches.
GeneratedFunction generate(const Model& model, const ParameterSet& params, Function function,
                           bool numeric = false, const Eigen::VectorXd& values = {},
                           Objective objective = Objective::Operations,
                           const Contacts& contacts = {});

/// How the Slotine-Li products are formed: from the columns of the regressor Y, or Y p by one
/// force pass with the parameters as inputs, and Y^T s by the reverse (adjoint) pass of s^T Y p.
enum class SlotineLiForm { Columns, PassColumns, ColumnsAdjoint, PassAdjoint };
const char* toString(SlotineLiForm f);

struct SlotineLiVariant {
  SlotineLiForm form;
  OpCount count;
};

/// The Slotine-Li products of an adaptive controller step, customised to the model: inputs q,
/// dq, the reference velocity dqr and acceleration ddqr, the sliding variable s and the estimate
/// p; outputs Y p (n entries), Y^T s (np entries) and, when `normalised`, |Y|^2 (the squared
/// Frobenius norm), with Y = Y(q, dq, dqr, ddqr) the Slotine-Li regressor of mindyn/slotine_li.hpp
/// in the parameters `params` (offsets: a unit column per joint). Of the forms of SlotineLiForm
/// the one with the fewest multiplications plus additions is kept; `variants` receives the count
/// of each.
GeneratedFunction generateSlotineLi(const Model& model, const ParameterSet& params, bool normalised,
                                    std::vector<SlotineLiVariant>* variants = nullptr);

/// Everything an emitter needs: the functions of one robot under one name.
struct GeneratedCode {
  std::string robot;  // model name, for the header comment
  std::string name;   // identifier prefix of the generated functions
  int n = 0;
  // A floating base (a free-flyer or planar joint on the fixed base): the sizes of q and of
  // dq, ddq, tau (otherwise both n), and the contact links' names and wrench axes.
  bool floating = false;
  int nq = 0, nv = 0;
  std::vector<std::string> contacts;
  bool contact_world = true;
  // A tree (empty for a serial chain): the joint names in the order of q, and each joint's
  // parent (Model::parents), for the header comment.
  std::vector<std::string> joints;
  std::vector<int> parents;
  std::vector<JointType> kinds;  // with a floating base: each joint's kind
  // Where rotor inertia and friction act (for the header comment): on the motors when
  // `motor_side`; the transmissions, q_m = T q with `motors` the rows of T (none: empty); and
  // the friction model.
  bool motor_side = false;
  std::vector<std::string> motors;
  Eigen::MatrixXd T;
  FrictionModel friction;
  ParameterSet params;
  Eigen::VectorXd values;  // the parameter values (baked in when numeric)
  bool numeric = false;
  Objective objective = Objective::Operations;
  std::vector<GeneratedFunction> functions;
};

/// Generates `functions` under `name` (a C identifier; throws ModelError otherwise).
/// `contacts`: the contact wrenches of a floating base's inverse dynamics (ModelError on a
/// fixed-base model, or a link index out of range or given twice).
GeneratedCode generateCode(const Model& model, const ParameterSet& params,
                           const std::vector<Function>& functions, const std::string& name,
                           bool numeric = false, const Eigen::VectorXd& values = {},
                           Objective objective = Objective::Operations,
                           const Contacts& contacts = {});

/// Sets the robot's name and joint count of `code`, for a tree its joints and parents, and where
/// rotor inertia and friction act.
void describeModel(GeneratedCode& code, const Model& model);

/// What the geometry snap changed, over all functions of `code`.
GeometrySnap geometrySnap(const GeneratedCode& code);

/// `name` if it is a valid C and Structured Text identifier, otherwise throws ModelError.
void checkIdentifier(const std::string& name);

}  // namespace mindyn::codegen
