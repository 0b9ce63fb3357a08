#include "mindyn/urdf.hpp"

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <vector>

#include "mindyn/spatial.hpp"

namespace mindyn {
namespace {

/// Collects console_bridge error messages instead of printing them.
class CaptureHandler : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char* /*filename*/,
           int /*line*/) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) messages.push_back(text);
  }
  std::vector<std::string> messages;
};

/// Serialises our use of console_bridge's global handler and level.
std::mutex& consoleMutex() {
  static std::mutex mutex;
  return mutex;
}

/// Parses with urdfdom, printing nothing; on failure returns nullptr and urdfdom's complaints.
urdf::ModelInterfaceSharedPtr parseQuietly(const std::string& xml, std::string* reason) {
  std::lock_guard<std::mutex> lock(consoleMutex());
  CaptureHandler handler;
  const console_bridge::LogLevel level = console_bridge::getLogLevel();
  console_bridge::useOutputHandler(&handler);
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_ERROR);
  urdf::ModelInterfaceSharedPtr model;
  try {
    model = urdf::parseURDF(xml);
  } catch (const std::exception& e) {
    handler.messages.push_back(e.what());
    model.reset();
  }
  console_bridge::restorePreviousOutputHandler();
  console_bridge::setLogLevel(level);
  if (!model) {
    std::string text;
    for (const std::string& m : handler.messages) {
      if (m.empty()) continue;
      if (!text.empty()) text += "; ";
      text += m;
    }
    *reason = text.empty() ? std::string("urdfdom rejected it") : text;
  }
  return model;
}

Eigen::Isometry3d toIsometry(const urdf::Pose& pose) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const Eigen::Quaterniond q(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
  if (q.norm() > 0.0) T.linear() = q.normalized().toRotationMatrix();
  T.translation() << pose.position.x, pose.position.y, pose.position.z;
  return T;
}

/// Deepest link (in joints below the root) accepted: a chain has at most kMaxModelJoints moving
/// joints, and fixed joints between them are a few each.
constexpr int kMaxTreeDepth = 4 * kMaxModelJoints;

bool isMoving(const urdf::Joint& j) { return j.type != urdf::Joint::FIXED; }

/// A moving joint the model can hold: not a mimic joint (whose coupling to another joint the
/// model has no place for).
bool isModelled(const urdf::Joint& j) { return isMoving(j) && !j.mimic; }

const char* urdfTypeName(int type) {
  switch (type) {
    case urdf::Joint::REVOLUTE:
      return "revolute";
    case urdf::Joint::CONTINUOUS:
      return "continuous";
    case urdf::Joint::PRISMATIC:
      return "prismatic";
    case urdf::Joint::FLOATING:
      return "floating";
    case urdf::Joint::PLANAR:
      return "planar";
    case urdf::Joint::FIXED:
      return "fixed";
    default:
      return "unknown";
  }
}

std::string joinNames(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "'" : ", '") + n + "'";
  return s;
}

/// Builds the Model once the URDF text has been parsed.
class Builder {
 public:
  Builder(const urdf::ModelInterface& urdf, std::string source)
      : urdf_(urdf), source_(std::move(source)) {}

  Model build(const std::string& tip_name) {
    root_ = urdf_.getRoot();
    if (!root_) fail("has no root link");
    checkTree();
    if (!tip_name.empty()) return buildChain(findTip(tip_name));
    std::vector<std::string> leaves;
    collectLeaves(root_, &leaves);
    if (leaves.empty()) {
      std::vector<std::string> mimic;
      for (const auto& [name, j] : urdf_.joints_)
        if (j && isMoving(*j)) mimic.push_back(name);
      if (mimic.empty()) fail("robot '" + urdf_.getName() + "' has no moving joint");
      fail("robot '" + urdf_.getName() + "' has no moving joint but mimic joints (" +
           joinNames(mimic) + "), which are not supported");
    }
    if (leaves.size() == 1) return buildChain(urdf_.getLink(leaves.front()));
    return buildTree();
  }

 private:
  /// The chain root -> `tip`; moving joints off it are locked and merged.
  Model buildChain(const urdf::LinkConstSharedPtr& tip) {
    // Root -> tip path, as links and as the joints entering them.
    const std::vector<urdf::LinkConstSharedPtr> path = pathTo(tip);
    for (const auto& l : path) on_path_.insert(l->name);

    Model model = emptyModel();
    Eigen::Isometry3d fixed = Eigen::Isometry3d::Identity();  // since the last moving link
    for (size_t i = 1; i < path.size(); ++i) {
      const urdf::Joint& uj = *path[i]->parent_joint;
      const Eigen::Isometry3d origin = jointOrigin(uj);
      if (!isMoving(uj)) {
        fixed = fixed * origin;
        continue;
      }
      addJoint(uj, fixed * origin, *path[i], &model);
      fixed.setIdentity();
    }
    if (model.joints.empty())
      fail("no moving joint between root link '" + root_->name + "' and tip link '" + tip->name +
           "'");
    model.tool = fixed;
    return finish(&model, "joints off the chain locked at q = 0 (clamped to limits) and merged: ");
  }

  /// The whole tree: every moving joint, depth-first from the root, children in the order of
  /// their joint names (urdfdom's order, which Pinocchio's URDF parser follows too). Mimic joints
  /// with no other moving joint below are locked and merged.
  Model buildTree() {
    Model model = emptyModel();
    addSubtree(*root_, -1, Eigen::Isometry3d::Identity(), &model);
    return finish(&model, "mimic joints locked at q = 0 (clamped to limits) and merged: ");
  }

  /// Adds the moving joints below `link` to `model`; `parent` is the index of the joint moving
  /// `link` (-1 for the base) and `fixed` the fixed joints' transform from its frame to `link`.
  void addSubtree(const urdf::Link& link, int parent, const Eigen::Isometry3d& fixed,
                  Model* model) {
    std::vector<urdf::LinkConstSharedPtr> children(link.child_links.begin(),
                                                   link.child_links.end());
    std::sort(children.begin(), children.end(), [](const auto& a, const auto& b) {
      return a->parent_joint->name < b->parent_joint->name;
    });
    for (const auto& child : children) {
      const urdf::Joint& uj = *child->parent_joint;
      if (!isMoving(uj)) {
        if (movingBelow(*child)) addSubtree(*child, parent, fixed * jointOrigin(uj), model);
        continue;  // else merged into the body above (or part of the base)
      }
      if (uj.mimic) {
        if (movingBelow(*child))
          fail("joint '" + uj.name + "' mimics joint '" + uj.mimic->joint_name +
               "', which is not supported, and moving joints hang below it; load a chain that "
               "avoids it with a tip link (tip= in Python and C++, --tip on the command line)");
        continue;  // locked at q = 0 and merged into the body above by accumulate()
      }
      on_path_.insert(child->name);
      addJoint(uj, fixed * jointOrigin(uj), *child, model);
      model->parents.push_back(parent);
      addSubtree(*child, model->nq() - 1, Eigen::Isometry3d::Identity(), model);
    }
  }

  Model emptyModel() const {
    Model model;
    model.name = urdf_.getName();
    model.source = source_;
    model.convention = "urdf";
    model.link_names.push_back(root_->name);
    return model;
  }

  /// Appends the moving joint `uj` (origin `pre` from its parent body's frame) and its child
  /// link `body` to `model`.
  void addJoint(const urdf::Joint& uj, const Eigen::Isometry3d& pre, const urdf::Link& body,
                Model* model) {
    Joint j;
    j.name = uj.name;
    if (uj.type == urdf::Joint::REVOLUTE || uj.type == urdf::Joint::CONTINUOUS)
      j.type = JointType::Revolute;
    else if (uj.type == urdf::Joint::PRISMATIC)
      j.type = JointType::Prismatic;
    else
      fail("joint '" + uj.name + "' has type '" + urdfTypeName(uj.type) +
           "', which is not supported (revolute, continuous, prismatic and fixed joints are)");
    if (uj.mimic)
      fail("joint '" + uj.name + "' mimics joint '" + uj.mimic->joint_name +
           "', which is not supported; load a chain that ends before it with a tip link (tip= "
           "in Python and C++, --tip on the command line), e.g. its parent link '" +
           uj.parent_link_name + "', which locks it at q = 0");
    const Eigen::Vector3d axis(uj.axis.x, uj.axis.y, uj.axis.z);
    for (int i = 0; i < 3; ++i) checkValue("joint '" + uj.name + "'", "axis", axis[i]);
    if (axis.norm() < 1e-12) fail("joint '" + uj.name + "' has a zero or invalid axis");
    j.axis = axis.normalized();
    j.pre = pre;
    if (uj.limits) {
      const urdf::JointLimits& lim = *uj.limits;
      const std::string who = "joint '" + uj.name + "'";
      checkValue(who, "lower limit", lim.lower);
      checkValue(who, "upper limit", lim.upper);
      checkValue(who, "velocity limit", lim.velocity);
      checkValue(who, "effort limit", lim.effort);
      // urdfdom reports absent lower/upper as 0/0 and absent velocity/effort as 0: not given.
      if (uj.type != urdf::Joint::CONTINUOUS && !(lim.lower == 0.0 && lim.upper == 0.0)) {
        j.limits.lower = lim.lower;
        j.limits.upper = lim.upper;
      }
      if (lim.velocity > 0.0) j.limits.velocity = lim.velocity;
      if (lim.effort > 0.0) j.limits.effort = lim.effort;
    }
    if (uj.dynamics) {
      checkValue("joint '" + uj.name + "'", "damping", uj.dynamics->damping);
      checkValue("joint '" + uj.name + "'", "friction", uj.dynamics->friction);
    }
    viscous_.push_back(uj.dynamics ? uj.dynamics->damping : 0.0);
    coulomb_.push_back(uj.dynamics ? uj.dynamics->friction : 0.0);
    model->joints.push_back(j);
    model->link_names.push_back(body.name);
    bodies_.push_back(&body);
  }

  /// Inertial and friction values of the joints added; `parents` emptied for a chain; `locked`
  /// introduces the joints locked and merged in the notes.
  Model finish(Model* model, const std::string& locked) {
    const int n = model->nq();
    model->inertial.setZero(10 * n);
    for (int k = 0; k < n; ++k) {
      Eigen::Matrix<double, 10, 1> body = Eigen::Matrix<double, 10, 1>::Zero();
      accumulate(*bodies_[k], Eigen::Isometry3d::Identity(), &body);
      model->inertial.segment<10>(10 * k) = body;
    }
    model->rotor_inertia.setZero(n);
    model->viscous = Eigen::Map<const Eigen::VectorXd>(viscous_.data(), n);
    model->coulomb = Eigen::Map<const Eigen::VectorXd>(coulomb_.data(), n);
    if (!locked_.empty()) model->notes = locked + joinNames(locked_);
    if (model->isSerial()) model->parents.clear();
    model->validate();
    return std::move(*model);
  }

  [[noreturn]] void fail(const std::string& what) const { throw ModelError(source_ + ": " + what); }

  /// Throws unless `value` is finite and within kMaxDescriptionValue; `who` and `what` name it.
  void checkValue(const std::string& who, const std::string& what, double value) const {
    if (!std::isfinite(value)) fail(who + ": " + what + " is not finite");
    if (std::abs(value) > kMaxDescriptionValue) {
      char buf[80];
      std::snprintf(buf, sizeof buf, " %.6g exceeds the bound %.6g on its magnitude", value,
                    kMaxDescriptionValue);
      fail(who + ": " + what + buf);
    }
  }

  Eigen::Isometry3d jointOrigin(const urdf::Joint& j) const {
    const urdf::Pose& o = j.parent_to_joint_origin_transform;
    const std::string who = "joint '" + j.name + "'";
    for (double v : {o.position.x, o.position.y, o.position.z}) checkValue(who, "origin xyz", v);
    for (double v : {o.rotation.x, o.rotation.y, o.rotation.z, o.rotation.w})
      if (!std::isfinite(v)) fail(who + ": origin rpy is not finite");
    return toIsometry(o);
  }

  /// Refuses what urdfdom lets through but is no tree: a joint whose parent is its child, a link
  /// entered by two joints, links that hang in a loop instead of below the root. After this,
  /// walking parents from any link ends at the root and walking children ends at leaves.
  void checkTree() const {
    std::map<std::string, std::vector<std::string>> entering;  // child link -> joints
    std::map<std::string, std::string> parent_of;              // child link -> parent link
    for (const auto& [name, j] : urdf_.joints_) {
      if (!j) continue;
      if (j->parent_link_name == j->child_link_name)
        fail("joint '" + name + "' has link '" + j->child_link_name +
             "' as both its parent and its child");
      entering[j->child_link_name].push_back(name);
      parent_of[j->child_link_name] = j->parent_link_name;
    }
    for (const auto& [link, joints] : entering)
      if (joints.size() > 1)
        fail("link '" + link + "' is the child of " + std::to_string(joints.size()) + " joints (" +
             joinNames(joints) +
             "); in a URDF every link but the root has exactly one parent joint");
    // Every link must be reached from the root; one that is not sits in a loop of joints.
    // The depth bound keeps the recursive walks below (merging, leaf search) shallow.
    std::set<std::string> reached{root_->name};
    std::vector<std::pair<urdf::LinkConstSharedPtr, int>> stack{{root_, 0}};
    while (!stack.empty()) {
      const auto [l, depth] = stack.back();
      stack.pop_back();
      if (depth > kMaxTreeDepth)
        fail("link '" + l->name + "' lies more than " + std::to_string(kMaxTreeDepth) +
             " joints below the root; deeper trees are not supported");
      for (const auto& c : l->child_links)
        if (c && reached.insert(c->name).second) stack.push_back({c, depth + 1});
    }
    for (const auto& [name, link] : urdf_.links_) {
      if (reached.count(name)) continue;
      // Each link has one parent, so walking up from here must come back to a link seen before.
      std::vector<std::string> walk{name};
      std::set<std::string> seen{name};
      for (auto it = parent_of.find(name); it != parent_of.end(); it = parent_of.find(it->second)) {
        if (!seen.insert(it->second).second) {
          const auto start = std::find(walk.begin(), walk.end(), it->second);
          std::vector<std::string> loop(walk.rbegin(), std::make_reverse_iterator(start)), joints;
          for (const std::string& l : loop) joints.push_back(entering[l].front());
          fail("joints " + joinNames(joints) + " form a loop through links " + joinNames(loop) +
               "; a URDF must be a tree");
        }
        walk.push_back(it->second);
      }
      fail("link '" + name + "' is not connected to the root link '" + root_->name + "'");
    }
  }

  /// The links from the root to `tip`, both included.
  std::vector<urdf::LinkConstSharedPtr> pathTo(const urdf::LinkConstSharedPtr& tip) const {
    std::vector<urdf::LinkConstSharedPtr> path;
    for (urdf::LinkConstSharedPtr l = tip; l; l = l->getParent()) {
      if (path.size() > urdf_.links_.size())  // unreachable after checkTree(); kept as a guard
        fail("the parents of link '" + tip->name + "' do not lead to the root");
      path.push_back(l);
    }
    std::reverse(path.begin(), path.end());
    return path;
  }

  /// True if the subtree below `link` contains a moving joint that is not a mimic joint.
  bool movingBelow(const urdf::Link& link) {
    const auto it = moving_below_.find(link.name);
    if (it != moving_below_.end()) return it->second;
    bool moving = false;
    for (const auto& c : link.child_links)
      if (isModelled(*c->parent_joint) || movingBelow(*c)) moving = true;
    moving_below_[link.name] = moving;
    return moving;
  }

  /// Links of moving (not mimic) joints whose subtrees hold only fixed or mimic joints.
  void collectLeaves(const urdf::LinkConstSharedPtr& link, std::vector<std::string>* leaves) {
    if (link != root_ && isModelled(*link->parent_joint) && !movingBelow(*link)) {
      leaves->push_back(link->name);
      return;
    }
    for (const auto& c : link->child_links) collectLeaves(c, leaves);
  }

  /// The link named `tip_name`, or a ModelError listing the links.
  urdf::LinkConstSharedPtr findTip(const std::string& tip_name) const {
    urdf::LinkConstSharedPtr tip = urdf_.getLink(tip_name);
    if (!tip) {
      std::vector<std::string> names;
      for (const auto& kv : urdf_.links_) names.push_back(kv.first);
      fail("tip link '" + tip_name + "' is not in robot '" + urdf_.getName() + "'; its links are " +
           joinNames(names));
    }
    return tip;
  }

  /// Motion of an off-chain joint locked at q = 0 clamped into its limits.
  Eigen::Isometry3d lockedMotion(const urdf::Joint& j) {
    Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
    if (!isMoving(j)) return M;
    locked_.push_back(j.name);
    double q = 0.0;
    const std::string who = "joint '" + j.name + "'";
    if (j.limits && j.type != urdf::Joint::CONTINUOUS) {
      checkValue(who, "lower limit", j.limits->lower);
      checkValue(who, "upper limit", j.limits->upper);
      if (j.limits->lower <= j.limits->upper)
        q = std::min(std::max(0.0, j.limits->lower), j.limits->upper);
    }
    const Eigen::Vector3d axis(j.axis.x, j.axis.y, j.axis.z);
    for (int i = 0; i < 3; ++i) checkValue(who, "axis", axis[i]);
    if (q == 0.0 || !(axis.norm() > 1e-12)) return M;
    if (j.type == urdf::Joint::REVOLUTE)
      M.linear() = Eigen::AngleAxisd(q, axis.normalized()).toRotationMatrix();
    else if (j.type == urdf::Joint::PRISMATIC)
      M.translation() = q * axis.normalized();
    return M;
  }

  /// Adds `link` and everything rigidly attached below it (in frame `body_T_link`) to `body`.
  void accumulate(const urdf::Link& link, const Eigen::Isometry3d& body_T_link,
                  Eigen::Matrix<double, 10, 1>* body) {
    if (link.inertial) {
      const urdf::Inertial& in = *link.inertial;
      const std::string who = "link '" + link.name + "'";
      checkValue(who, "mass", in.mass);
      if (in.mass < 0.0) fail(who + " has mass " + std::to_string(in.mass));
      for (double v : {in.origin.position.x, in.origin.position.y, in.origin.position.z})
        checkValue(who, "inertial origin xyz", v);
      for (double v :
           {in.origin.rotation.x, in.origin.rotation.y, in.origin.rotation.z, in.origin.rotation.w})
        if (!std::isfinite(v)) fail(who + ": inertial origin rpy is not finite");
      const Eigen::Isometry3d frame = toIsometry(in.origin);
      Eigen::Matrix3d Ic;
      Ic << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
      if (!Ic.allFinite()) fail(who + " has a non-finite inertia");
      for (int i = 0; i < 9; ++i) checkValue(who, "inertia", Ic(i));
      const Eigen::Matrix<double, 10, 1> p =
          inertialFromUrdf(in.mass, frame.translation(), frame.linear(), Ic);
      *body += transformInertial(p, body_T_link);
    }
    for (const auto& child : link.child_links) {
      const urdf::Joint& j = *child->parent_joint;
      if (isMoving(j) && on_path_.count(child->name)) continue;  // the next chain body
      const Eigen::Isometry3d T = body_T_link * jointOrigin(j) * lockedMotion(j);
      accumulate(*child, T, body);
    }
  }

  const urdf::ModelInterface& urdf_;
  const std::string source_;
  urdf::LinkConstSharedPtr root_;
  std::set<std::string> on_path_;  // links of the model's moving joints (chain: the whole path)
  std::map<std::string, bool> moving_below_;
  std::vector<std::string> locked_;
  std::vector<const urdf::Link*> bodies_;  // child links of the model's joints
  std::vector<double> viscous_, coulomb_;
};

}  // namespace

Eigen::Matrix<double, 10, 1> transformInertial(const Eigen::Matrix<double, 10, 1>& inertial,
                                               const Eigen::Isometry3d& parent_T_child) {
  const Eigen::Matrix3d R = parent_T_child.linear();
  const Eigen::Vector3d p = parent_T_child.translation();
  const double m = inertial[9];
  const Eigen::Vector3d Rh = R * inertial.segment<3>(6);
  const Eigen::Matrix3d P = skew(p);
  const Eigen::Matrix3d H = skew(Rh);
  const Eigen::Matrix3d I = R * inertiaTensor(inertial) * R.transpose() - P * H - H * P - m * P * P;
  const Eigen::Vector3d h = Rh + m * p;
  Eigen::Matrix<double, 10, 1> out;
  out << I(0, 0), I(0, 1), I(0, 2), I(1, 1), I(1, 2), I(2, 2), h.x(), h.y(), h.z(), m;
  return out;
}

Model parseUrdf(const std::string& xml, const std::string& tip, const std::string& source) {
  try {
    requireUtf8(xml, source);
    std::string reason;
    const urdf::ModelInterfaceSharedPtr urdf = parseQuietly(xml, &reason);
    if (!urdf) throw ModelError(source + ": not a valid URDF: " + reason);
    return Builder(*urdf, source).build(tip);
  } catch (const ModelError& e) {
    throw ModelError(escapeControl(e.what()));  // names from the file may hold line breaks
  }
}

Model loadUrdf(const std::string& path, const std::string& tip) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw FileError("URDF file '" + path + "' does not exist");
  if (fs::is_directory(path, ec)) throw FileError("URDF file '" + path + "' is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError("URDF file '" + path + "' cannot be read");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw FileError("URDF file '" + path + "' cannot be read");
  return parseUrdf(text.str(), tip, path);
}

}  // namespace mindyn
