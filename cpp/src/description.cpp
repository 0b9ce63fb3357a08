#include "mindyn/description.hpp"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/parser.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "mindyn/spatial.hpp"

namespace mindyn {

namespace {

std::string formatNumber(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

/// `SOURCE:LINE:COLUMN` (both from 1) of a place in a YAML text, as the Python readers give
/// it; `SOURCE` alone without a place.
std::string at(const std::string& source, const YAML::Mark& mark) {
  if (mark.is_null() || mark.line < 0) return source;
  return source + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
}

struct Ctx {
  std::string source;
  std::string where;  // e.g. "joint 2 ('shoulder')"
  [[noreturn]] void fail(const std::string& msg, const YAML::Node& node = YAML::Node()) const {
    const std::string loc = node.IsDefined() ? at(source, node.Mark()) : source;
    throw ModelError(loc + ": " + (where.empty() ? "" : where + ": ") + msg);
  }
};

const char* kindName(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a mapping";
    case YAML::NodeType::Null:
      return "empty";
    default:
      return "a scalar";
  }
}

/// Tags a description may carry: none, or YAML's core-schema ones. Anything else (language
/// specific objects such as !!python/object, binary data, application tags) is refused.
bool plainTag(const std::string& tag) {
  static const std::set<std::string> core = {"",
                                             "?",
                                             "!",
                                             "tag:yaml.org,2002:str",
                                             "tag:yaml.org,2002:int",
                                             "tag:yaml.org,2002:float",
                                             "tag:yaml.org,2002:bool",
                                             "tag:yaml.org,2002:null",
                                             "tag:yaml.org,2002:seq",
                                             "tag:yaml.org,2002:map"};
  return core.count(tag) > 0;
}

/// Checks the whole document once: only core tags, keys that are plain scalars, no key twice in
/// one mapping (yaml-cpp keeps duplicates and answers lookups with the first). `budget` bounds the
/// nodes visited, so that aliases cannot make the walk exponential.
void checkTree(const Ctx& c, const YAML::Node& node, long* budget, int depth) {
  if (--*budget < 0)
    c.fail(
        "the document expands (through aliases) to more nodes than its text holds; a robot "
        "description does not need that",
        node);
  if (depth > 64) c.fail("the document is nested more than 64 levels deep", node);
  if (!plainTag(node.Tag()))
    c.fail("YAML tag '" + node.Tag() + "' is not supported (plain values, lists and mappings only)",
           node);
  if (node.IsSequence()) {
    for (const YAML::Node& item : node) checkTree(c, item, budget, depth + 1);
  } else if (node.IsMap()) {
    std::set<std::string> seen;
    for (const auto& kv : node) {
      if (!kv.first.IsScalar())
        c.fail(std::string("a key must be plain text, got ") + kindName(kv.first), kv.first);
      checkTree(c, kv.first, budget, depth + 1);
      const std::string key = kv.first.Scalar();
      if (!seen.insert(key).second) c.fail("key '" + key + "' appears twice", kv.first);
      checkTree(c, kv.second, budget, depth + 1);
    }
  }
}

void checkKeys(const Ctx& c, const YAML::Node& node, const std::set<std::string>& allowed,
               const std::string& what) {
  if (!node.IsMap()) c.fail(what + " must be a mapping, got " + kindName(node), node);
  for (const auto& kv : node) {
    const std::string key = kv.first.Scalar();
    if (!allowed.count(key)) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      c.fail("unknown key '" + key + "' in " + what + " (allowed: " + list + ")", kv.first);
    }
  }
}

double number(const Ctx& c, const YAML::Node& node, const std::string& key) {
  if (!node.IsScalar()) c.fail("'" + key + "' must be a number, got " + kindName(node), node);
  double v = 0.0;
  try {
    v = node.as<double>();
  } catch (const YAML::Exception&) {
    c.fail("'" + key + "' must be a number, got '" + node.Scalar() + "'", node);
  }
  if (!std::isfinite(v)) c.fail("'" + key + "' is not finite", node);
  if (std::abs(v) > kMaxDescriptionValue)
    c.fail("'" + key + "' = " + node.Scalar() + " exceeds the bound " +
               formatNumber(kMaxDescriptionValue) + " on the magnitude of a description value",
           node);
  return v;
}

/// The text of a scalar entry (numbers given as text are taken as written).
std::string text(const Ctx& c, const YAML::Node& node, const std::string& key) {
  if (!node.IsScalar()) c.fail("'" + key + "' must be text, got " + kindName(node), node);
  return node.Scalar();
}

std::string text(const Ctx& c, const YAML::Node& map, const std::string& key,
                 const std::string& def) {
  const YAML::Node n = map[key];
  return n.IsDefined() && !n.IsNull() ? text(c, n, key) : def;
}

bool boolean(const Ctx& c, const YAML::Node& node, const std::string& key) {
  bool b = false;
  if (!node.IsScalar() || !YAML::convert<bool>::decode(node, b))
    c.fail("'" + key + "' must be true or false", node);
  return b;
}

/// The number at `key` of `map`, `def` if the key is absent. A key written without a value
/// (`xx:` or `xx: ~`) is refused: it is a number left out, not a request for the default.
double optional(const Ctx& c, const YAML::Node& map, const std::string& key, double def) {
  const YAML::Node n = map[key];
  if (!n.IsDefined()) return def;
  if (n.IsNull())
    c.fail("'" + key + "' has no value; give a number, or leave the key out for its default", n);
  return number(c, n, key);
}

/// An optional rotor inertia or friction entry (default 0), refused where negative.
double driveTerm(const Ctx& c, const YAML::Node& map, const std::string& key) {
  const double v = optional(c, map, key, 0.0);
  if (v < 0.0)
    c.fail("'" + key + "' is " + formatNumber(v) + "; rotor inertia and friction are >= 0",
           map[key]);
  return v;
}

Eigen::Vector3d vec3(const Ctx& c, const YAML::Node& node, const std::string& key) {
  if (!node.IsSequence() || node.size() != 3)
    c.fail("'" + key + "' must be a list of 3 numbers", node);
  return {number(c, node[0], key), number(c, node[1], key), number(c, node[2], key)};
}

// Rotations by multiples of 90 degrees come out of sin/cos with 1e-17 residues: cleaned here,
// before they multiply lengths (a residue times a length of 1e6 m is no longer below clean()'s
// level, and makes exactly degenerate geometry look near-degenerate).
Eigen::Matrix3d exactRightAngles(Eigen::Matrix3d R) {
  for (int i = 0; i < 9; ++i)
    if (std::abs(R.data()[i]) < 1e-15) R.data()[i] = 0.0;
  return R;
}
Eigen::Isometry3d rotX(double a) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = exactRightAngles(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix());
  return T;
}
Eigen::Isometry3d rotZ(double a) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = exactRightAngles(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix());
  return T;
}
Eigen::Isometry3d trans(double x, double y, double z) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() << x, y, z;
  return T;
}

// Rotations that are exact multiples of 90 degrees come out of sin/cos with 1e-17 residues;
// clean them so that exactly degenerate geometry stays exactly degenerate.
void clean(Eigen::Isometry3d& T) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j)
      if (std::abs(T.matrix()(i, j)) < 1e-15) T.matrix()(i, j) = 0.0;
}

Eigen::Matrix<double, 10, 1> readInertial(const Ctx& c, const YAML::Node& node) {
  if (!node.IsMap()) c.fail("'inertial' must be a mapping", node);
  if (node["mass"].IsDefined()) {
    checkKeys(c, node, {"mass", "com", "inertia"}, "inertial");
    const double m = number(c, node["mass"], "mass");
    if (m < 0) c.fail("mass is negative", node["mass"]);
    const Eigen::Vector3d com =
        node["com"].IsDefined() ? vec3(c, node["com"], "com") : Eigen::Vector3d::Zero();
    Eigen::Matrix3d I = Eigen::Matrix3d::Zero();
    if (node["inertia"].IsDefined()) {
      const YAML::Node in = node["inertia"];
      checkKeys(c, in, {"xx", "yy", "zz", "xy", "xz", "yz"}, "inertia");
      I(0, 0) = optional(c, in, "xx", 0);
      I(1, 1) = optional(c, in, "yy", 0);
      I(2, 2) = optional(c, in, "zz", 0);
      I(0, 1) = I(1, 0) = optional(c, in, "xy", 0);
      I(0, 2) = I(2, 0) = optional(c, in, "xz", 0);
      I(1, 2) = I(2, 1) = optional(c, in, "yz", 0);
    }
    return inertialFromCom(m, com, I);
  }
  std::set<std::string> names(std::begin(kInertialNames), std::end(kInertialNames));
  checkKeys(c, node, names, "inertial (give either mass/com/inertia or XX..M)");
  Eigen::Matrix<double, 10, 1> p;
  for (int i = 0; i < 10; ++i) p[i] = optional(c, node, kInertialNames[i], 0.0);
  if (p[9] < 0) c.fail("mass M is negative", node[kInertialNames[9]]);
  return p;
}

}  // namespace

namespace {

/// Records where documents start and where quoted scalars start, nothing else.
class DocumentStarts : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark& mark) override { starts.push_back(mark); }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t,
                const std::string&) override {
    if (tag == "!") quoted.push_back(mark);  // the non-specific tag of a quoted scalar
  }
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}
  std::vector<YAML::Mark> starts;
  std::vector<YAML::Mark> quoted;
};

/// Whether the quoted scalar opening at `pos` of `yaml` is closed: yaml-cpp takes a quote left
/// open as a scalar running to the end of the text, where YAML (and PyYAML) refuse it. In double
/// quotes a backslash escapes the next character; in single quotes a doubled quote is one.
bool quoteClosed(const std::string& yaml, std::size_t pos) {
  if (pos >= yaml.size() || (yaml[pos] != '"' && yaml[pos] != '\'')) return true;  // not a quote
  const char q = yaml[pos];
  for (std::size_t k = pos + 1; k < yaml.size(); ++k) {
    if (q == '"' && yaml[k] == '\\') {
      ++k;
    } else if (yaml[k] == q) {
      if (q == '\'' && k + 1 < yaml.size() && yaml[k + 1] == '\'') {
        ++k;
      } else {
        return true;
      }
    }
  }
  return false;
}

/// Where a second document starts in `yaml` (`second`, or a null mark), after checking that
/// every quoted scalar of the first two documents is closed. Parses at most two documents:
/// YAML::LoadAll of this yaml-cpp can loop forever, allocating, on a stray ',' or ']'.
YAML::Mark secondDocument(const std::string& yaml, const std::string& source) {
  std::istringstream in(yaml);
  YAML::Parser parser(in);
  DocumentStarts starts;
  for (int k = 0; k < 2 && parser.HandleNextDocument(starts); ++k) {
  }
  for (const YAML::Mark& m : starts.quoted)
    if (m.pos >= 0 && !quoteClosed(yaml, static_cast<std::size_t>(m.pos)))
      throw ModelError(at(source, m) +
                       ": not valid YAML: the quoted text starting here is never closed");
  return starts.starts.size() > 1 ? starts.starts[1] : YAML::Mark::null_mark();
}

Model build(const Ctx& start, const YAML::Node& root);
Model parseDocument(const std::string& yaml, const std::string& source);

}  // namespace

Model parseYaml(const std::string& yaml, const std::string& source) {
  try {
    return parseDocument(yaml, source);
  } catch (const ModelError& e) {
    throw ModelError(escapeControl(e.what()));  // names from the file may hold line breaks
  }
}

namespace {

Model parseDocument(const std::string& yaml, const std::string& source) {
  Ctx c{source, ""};
  requireUtf8(yaml, source);
  YAML::Node root;
  YAML::Mark second;  // where a second document starts, if there is one
  try {
    root = YAML::Load(yaml);
    second = secondDocument(yaml, source);
  } catch (const YAML::Exception& e) {
    throw ModelError(at(source, e.mark) + ": not valid YAML: " + e.msg);
  }
  if (!root.IsMap()) c.fail("a robot description must be a YAML mapping with a 'joints' list");
  if (!second.is_null())
    throw ModelError(at(source, second) +
                     ": a second YAML document starts here; a robot description is one document");
  long budget = 4 * static_cast<long>(yaml.size()) + 16;
  checkTree(c, root, &budget, 0);
  try {
    return build(c, root);
  } catch (const YAML::Exception& e) {
    // Every entry is type-checked before conversion; this is the backstop for anything missed.
    throw ModelError(at(source, e.mark) + ": " + e.msg);
  }
}

/// A list of numbers of length `size` (motors or joints).
std::vector<double> numbers(const Ctx& c, const YAML::Node& node, const std::string& key,
                            size_t size) {
  if (!node.IsSequence() || node.size() != size)
    c.fail("'" + key + "' must be a list of " + std::to_string(size) + " numbers", node);
  std::vector<double> v;
  for (const auto& x : node) v.push_back(number(c, x, key));
  return v;
}

/// `transmissions:` either {matrix: [[...], ...] (n_m rows of n), motors: [names], offset: [c],
/// torque_constant: [K_t], rotor_inertia: [..], viscous: [..], coulomb: [..]}, or a list of
/// motors {name, joints: {joint: coefficient, ...}, offset, torque_constant, rotor_inertia,
/// viscous, coulomb}: q_m = T q + c (see transmission.hpp), the motors' own rotor inertia and
/// friction (motor side, Transmission).
Transmission readTransmissions(Ctx c, const YAML::Node& root, const Model& model) {
  const YAML::Node node = root["transmissions"];
  const size_t n = model.joints.size();
  Transmission tr;
  tr.format = "yaml";
  std::vector<std::vector<double>> rows;
  std::vector<double> offsets, constants;
  std::vector<double> motor_terms[3];  // rotor_inertia, viscous, coulomb of each motor
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  if (node.IsMap()) {
    c.where = "transmissions";
    checkKeys(
        c, node,
        {"matrix", "motors", "offset", "torque_constant", "rotor_inertia", "viscous", "coulomb"},
        "transmissions");
    const YAML::Node M = node["matrix"];
    if (!M.IsDefined()) c.fail("has no 'matrix' (n_m rows of " + std::to_string(n) + ")", node);
    if (!M.IsSequence() || M.size() == 0)
      c.fail("'matrix' must be a list of rows (one per motor) of " + std::to_string(n) + " numbers",
             M);
    for (const auto& r : M) rows.push_back(numbers(c, r, "matrix", n));
    const size_t m = rows.size();
    for (size_t i = 0; i < m; ++i) tr.motors.push_back("motor" + std::to_string(i + 1));
    if (node["motors"].IsDefined()) {
      const YAML::Node names = node["motors"];
      if (!names.IsSequence() || names.size() != m)
        c.fail("'motors' must be a list of " + std::to_string(m) + " names", names);
      for (size_t i = 0; i < m; ++i) tr.motors[i] = text(c, names[i], "motors");
    }
    offsets = node["offset"].IsDefined() ? numbers(c, node["offset"], "offset", m)
                                         : std::vector<double>(m, 0.0);
    constants = node["torque_constant"].IsDefined()
                    ? numbers(c, node["torque_constant"], "torque_constant", m)
                    : std::vector<double>(m, kNaN);
    for (const auto& [key, v] :
         {std::pair<const char*, std::vector<double>*>{"rotor_inertia", &motor_terms[0]},
          {"viscous", &motor_terms[1]},
          {"coulomb", &motor_terms[2]}})
      if (node[key].IsDefined()) {
        *v = numbers(c, node[key], key, m);
        for (size_t i = 0; i < m; ++i)
          if ((*v)[i] < 0.0)
            c.fail("'" + std::string(key) + "' of motor " + std::to_string(i + 1) + " is " +
                       formatNumber((*v)[i]) + "; rotor inertia and friction are >= 0",
                   node[key][i]);
      }
  } else if (node.IsSequence() && node.size() > 0) {
    std::map<std::string, size_t> index;
    for (size_t k = 0; k < n; ++k) index[model.joints[k].name] = k;
    size_t i = 0;
    for (const auto& e : node) {
      c.where = "transmissions, motor " + std::to_string(++i);
      if (!e.IsMap()) c.fail("a motor must be a mapping, got " + std::string(kindName(e)), e);
      checkKeys(
          c, e,
          {"name", "joints", "offset", "torque_constant", "rotor_inertia", "viscous", "coulomb"},
          "a motor");
      tr.motors.push_back(text(c, e, "name", "motor" + std::to_string(i)));
      c.where += " ('" + tr.motors.back() + "')";
      const YAML::Node js = e["joints"];
      if (!js.IsDefined() || !js.IsMap() || js.size() == 0)
        c.fail("'joints' must map joint names to the motor's coefficients, e.g. {j1: 100}",
               js.IsDefined() ? js : e);
      std::vector<double> row(n, 0.0);
      for (const auto& kv : js) {
        const std::string j = kv.first.Scalar();
        const auto it = index.find(j);
        if (it == index.end()) c.fail("joint '" + j + "' is not a joint of the robot", kv.first);
        row[it->second] = number(c, kv.second, j);
      }
      rows.push_back(row);
      offsets.push_back(optional(c, e, "offset", 0.0));
      constants.push_back(optional(c, e, "torque_constant", kNaN));
      const char* keys[3] = {"rotor_inertia", "viscous", "coulomb"};
      for (int t = 0; t < 3; ++t) {
        motor_terms[t].resize(i - 1, kNaN);  // the motors before, without
        motor_terms[t].push_back(e[keys[t]].IsDefined() ? driveTerm(c, e, keys[t]) : kNaN);
      }
    }
  } else {
    c.where.clear();
    c.fail(
        "'transmissions' must be a mapping {matrix, motors, offset, torque_constant, "
        "rotor_inertia, viscous, coulomb} or a list of motors {name, joints: {joint: "
        "coefficient}, offset, torque_constant, rotor_inertia, viscous, coulomb}",
        node);
  }
  const auto m = static_cast<Eigen::Index>(rows.size());
  tr.T.resize(m, static_cast<Eigen::Index>(n));
  for (Eigen::Index r = 0; r < m; ++r)
    for (size_t k = 0; k < n; ++k) tr.T(r, static_cast<Eigen::Index>(k)) = rows[r][k];
  tr.offset = Eigen::Map<const Eigen::VectorXd>(offsets.data(), m);
  tr.torque_constant = Eigen::Map<const Eigen::VectorXd>(constants.data(), m);
  tr.types.assign(static_cast<size_t>(m), "matrix");
  Eigen::VectorXd* fields[3] = {&tr.rotor_inertia, &tr.viscous, &tr.coulomb};
  for (int t = 0; t < 3; ++t)
    if (std::any_of(motor_terms[t].begin(), motor_terms[t].end(),
                    [](double x) { return !std::isnan(x); })) {
      motor_terms[t].resize(static_cast<size_t>(m), kNaN);
      *fields[t] = Eigen::Map<const Eigen::VectorXd>(motor_terms[t].data(), m);
    }
  c.where.clear();
  const std::string who = at(c.source, node.Mark()) + ": transmissions";
  tr.validate(model.joints, who);
  return tr;
}

Model build(const Ctx& start, const YAML::Node& root) {
  Ctx c = start;
  const std::string source = c.source;
  checkKeys(c, root,
            {"name", "description", "source", "notes", "convention", "angle_unit", "gravity",
             "synthetic_inertia", "joints", "tool", "transmissions", "drive_side"},
            "the description");
  Model model;
  model.name = text(c, root, "name", "robot");
  model.source = source;
  model.notes = text(c, root, "notes", "");
  text(c, root, "description", "");
  text(c, root, "source", "");
  if (root["synthetic_inertia"].IsDefined())
    model.synthetic_inertia = boolean(c, root["synthetic_inertia"], "synthetic_inertia");
  const std::string conv = text(c, root, "convention", "");
  if (conv != "dh" && conv != "mdh")
    c.fail("'convention' must be 'dh' or 'mdh'" +
               (conv.empty() ? std::string(" (missing)") : ", got '" + conv + "'"),
           root["convention"]);
  model.convention = conv;
  const std::string unit = text(c, root, "angle_unit", "rad");
  if (unit != "rad" && unit != "deg")
    c.fail("'angle_unit' must be 'rad' or 'deg'", root["angle_unit"]);
  const double ang = unit == "deg" ? kPi / 180.0 : 1.0;
  if (root["gravity"].IsDefined()) model.gravity = vec3(c, root["gravity"], "gravity");

  const YAML::Node joints = root["joints"];
  if (!joints.IsDefined() || !joints.IsSequence() || joints.size() == 0)
    c.fail("'joints' must be a non-empty list", joints);
  if (joints.size() > static_cast<size_t>(kMaxModelJoints))
    c.fail("'joints' lists " + std::to_string(joints.size()) + " joints; at most " +
               std::to_string(kMaxModelJoints) + " are supported",
           joints);
  const int n = static_cast<int>(joints.size());
  model.inertial = Eigen::VectorXd::Zero(10 * n);
  model.rotor_inertia = Eigen::VectorXd::Zero(n);
  model.viscous = Eigen::VectorXd::Zero(n);
  model.coulomb = Eigen::VectorXd::Zero(n);
  model.link_names.push_back("base");
  const std::set<std::string> geo = conv == "dh"
                                        ? std::set<std::string>{"a", "alpha", "d", "theta"}
                                        : std::set<std::string>{"alpha", "d", "theta", "r"};
  std::vector<int> parents;
  for (int k = 0; k < n; ++k) {
    const YAML::Node jn = joints[k];
    Joint j;
    c.where = "joint " + std::to_string(k + 1);
    if (!jn.IsMap()) c.fail("a joint must be a mapping, got " + std::string(kindName(jn)), jn);
    j.name = text(c, jn, "name", "joint" + std::to_string(k + 1));
    for (int e = 0; e < k; ++e)
      if (model.joints[static_cast<size_t>(e)].name == j.name)
        c.fail("the name '" + j.name + "' is joint " + std::to_string(e + 1) +
                   "'s too; joint names must be unique",
               jn["name"].IsDefined() ? jn["name"] : jn);
    c.where = "joint " + std::to_string(k + 1) + " ('" + j.name + "')";
    std::set<std::string> allowed = geo;
    allowed.insert({"name", "type", "limits", "drive", "inertial", "rotor_inertia", "friction",
                    "link", "parent"});
    checkKeys(c, jn, allowed, "the joint");
    const std::string type = text(c, jn, "type", "revolute");
    if (type == "revolute" || type == "continuous")
      j.type = JointType::Revolute;
    else if (type == "prismatic")
      j.type = JointType::Prismatic;
    else if (type == "spherical")
      j.type = JointType::Spherical;
    else if (type == "universal")
      j.type = JointType::Universal;
    else if (type == "cylindrical")
      j.type = JointType::Cylindrical;
    else if (type == "planar")
      j.type = JointType::Planar;
    else if (type == "floating")
      j.type = JointType::FreeFlyer;
    else
      c.fail("joint type '" + escapeControl(type) +
                 "' is not supported (revolute, continuous, prismatic, spherical, universal, "
                 "cylindrical, planar or floating)",
             jn["type"]);
    if (!j.singleDof())
      for (const char* key : {"limits", "drive", "rotor_inertia", "friction"})
        if (jn[key].IsDefined())
          c.fail(std::string("'") + key +
                     "' is given for revolute and prismatic joints only, not "
                     "for this " +
                     type + " joint",
                 jn[key]);
    // The joint carrying the parent link: 1-based index of an earlier joint, 0 for the base
    // (default: the joint before, a serial chain).
    const double parent = optional(c, jn, "parent", k);
    if (parent != std::floor(parent) || parent < 0 || parent > k)
      c.fail("'parent' must be 0 (the base) or the number of an earlier joint (1 to " +
                 std::to_string(k) + ")",
             jn["parent"]);
    parents.push_back(static_cast<int>(parent) - 1);
    DHRow row;
    if (conv == "dh") {
      row.a = optional(c, jn, "a", 0);
      row.alpha = optional(c, jn, "alpha", 0) * ang;
      row.d = optional(c, jn, "d", 0);
      row.theta = optional(c, jn, "theta", 0) * ang;
      j.pre = Eigen::Isometry3d::Identity();
      j.post = rotZ(row.theta) * trans(0, 0, row.d) * trans(row.a, 0, 0) * rotX(row.alpha);
    } else {
      // MDH: alpha_j, d_j (along x), theta_j, r_j; stored as alpha, a, theta, d.
      row.alpha = optional(c, jn, "alpha", 0) * ang;
      row.a = optional(c, jn, "d", 0);
      row.theta = optional(c, jn, "theta", 0) * ang;
      row.d = optional(c, jn, "r", 0);
      j.pre = rotX(row.alpha) * trans(row.a, 0, 0) * rotZ(row.theta) * trans(0, 0, row.d);
      j.post = Eigen::Isometry3d::Identity();
    }
    clean(j.pre);
    clean(j.post);
    j.axis = Eigen::Vector3d::UnitZ();
    model.dh.push_back(row);
    if (jn["limits"].IsDefined()) {
      const YAML::Node l = jn["limits"];
      checkKeys(c, l, {"lower", "upper", "velocity", "acceleration", "effort"}, "limits");
      const double s = j.type == JointType::Revolute ? ang : 1.0;
      const double nan = std::numeric_limits<double>::quiet_NaN();
      j.limits.lower = optional(c, l, "lower", nan) * s;
      j.limits.upper = optional(c, l, "upper", nan) * s;
      j.limits.velocity = optional(c, l, "velocity", nan) * s;
      j.limits.acceleration = optional(c, l, "acceleration", nan) * s;
      j.limits.effort = optional(c, l, "effort", nan);
      if (j.limits.lower > j.limits.upper) c.fail("lower limit above upper limit", l);
      for (const char* key : {"velocity", "acceleration", "effort"})
        if (optional(c, l, key, 0.0) < 0.0)  // as a URDF's <limit> (urdf.cpp)
          c.fail(std::string("limits: '") + key + "' is " + l[key].as<std::string>() +
                     ": a limit on the magnitude cannot be negative",
                 l[key]);
    }
    if (jn["drive"].IsDefined()) {
      checkKeys(c, jn["drive"], {"rated_torque", "gear_ratio", "torque_constant"}, "drive");
      j.drive.rated_torque = optional(c, jn["drive"], "rated_torque", j.drive.rated_torque);
      j.drive.gear_ratio = optional(c, jn["drive"], "gear_ratio", j.drive.gear_ratio);
      j.drive.torque_constant =
          optional(c, jn["drive"], "torque_constant", j.drive.torque_constant);
    }
    if (jn["inertial"].IsDefined())
      model.inertial.segment<10>(10 * k) = readInertial(c, jn["inertial"]);
    model.rotor_inertia[k] = driveTerm(c, jn, "rotor_inertia");
    if (jn["friction"].IsDefined()) {
      checkKeys(c, jn["friction"], {"viscous", "coulomb"}, "friction");
      model.viscous[k] = driveTerm(c, jn["friction"], "viscous");
      model.coulomb[k] = driveTerm(c, jn["friction"], "coulomb");
    }
    model.link_names.push_back(text(c, jn, "link", "link" + std::to_string(k + 1)));
    model.joints.push_back(j);
  }
  c.where.clear();
  for (int k = 0; k < n; ++k)
    if (parents[k] != k - 1) model.parents = parents;
  if (root["tool"].IsDefined()) {
    const YAML::Node t = root["tool"];
    checkKeys(c, t, {"xyz", "rpy"}, "tool");
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    if (t["xyz"].IsDefined()) T.translation() = vec3(c, t["xyz"], "xyz");
    if (t["rpy"].IsDefined()) {
      const Eigen::Vector3d rpy = vec3(c, t["rpy"], "rpy") * ang;
      T.linear() = (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
                    Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
                    Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
                       .toRotationMatrix();
    }
    model.tool = T;
  }
  if (root["transmissions"].IsDefined()) model.transmission = readTransmissions(c, root, model);
  // Where each joint's rotor_inertia and friction act (Model::drive_terms_on_motors): with
  // transmissions, on motor k of the joint's slot k ("motor", the default) or on the joint
  // (for more motors than joints the only side: a motor's terms then have no joint slot).
  const bool square = model.transmission.nm() == model.nq();
  const std::string side = text(c, root, "drive_side", "");
  if (!side.empty()) {
    if (side != "motor" && side != "joint")
      c.fail("'drive_side' must be 'motor' or 'joint', got '" + escapeControl(side) + "'",
             root["drive_side"]);
    if (side == "motor" && model.transmission.empty())
      c.fail("'drive_side: motor' needs 'transmissions'", root["drive_side"]);
    if (side == "motor" && !square)
      c.fail("'drive_side: motor' needs one motor per joint; the transmissions have " +
                 std::to_string(model.transmission.nm()) + " motors for " +
                 std::to_string(model.nq()) + " joints (use 'drive_side: joint')",
             root["drive_side"]);
    model.drive_terms_on_motors = side == "motor";
  }
  model.validate();
  return model;
}

}  // namespace

Model loadYaml(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw FileError("robot description '" + path + "' does not exist or cannot be read");
  std::stringstream ss;
  ss << in.rdbuf();
  return parseYaml(ss.str(), path);
}

Model planarArm(int n, bool vertical, double length, double mass) {
  if (n < 1) throw ModelError("a planar arm needs at least one joint, got " + std::to_string(n));
  if (n > kMaxModelJoints)
    throw ModelError("a planar arm has at most " + std::to_string(kMaxModelJoints) +
                     " joints, got " + std::to_string(n));
  if (!(length > 0) || !(mass > 0))
    throw ModelError("planar arm: length and mass must be positive");
  Model model;
  model.name = "planar" + std::to_string(n) + (vertical ? "" : "h");
  model.source = "generated";
  model.convention = "mdh";
  model.notes = std::string("uniform rods of ") + std::to_string(length) + " m, " +
                std::to_string(mass) + " kg; " +
                (vertical ? "vertical plane (axes perpendicular to gravity)"
                          : "horizontal plane (axes parallel to gravity)");
  model.inertial = Eigen::VectorXd::Zero(10 * n);
  model.rotor_inertia = Eigen::VectorXd::Zero(n);
  model.viscous = Eigen::VectorXd::Zero(n);
  model.coulomb = Eigen::VectorXd::Zero(n);
  model.link_names.push_back("base");
  const double radius = 0.02;
  for (int k = 0; k < n; ++k) {
    Joint j;
    j.name = "joint" + std::to_string(k + 1);
    DHRow row;
    row.alpha = (k == 0 && vertical) ? kPi / 2 : 0.0;
    row.a = k == 0 ? 0.0 : length;
    j.pre = rotX(row.alpha) * trans(row.a, 0, 0);
    clean(j.pre);
    j.limits.lower = -kPi;
    j.limits.upper = kPi;
    j.limits.velocity = kPi;
    j.limits.acceleration = 4 * kPi;
    model.dh.push_back(row);
    model.joints.push_back(j);
    model.link_names.push_back("link" + std::to_string(k + 1));
    Eigen::Matrix3d Ic = Eigen::Matrix3d::Zero();
    Ic(0, 0) = 0.5 * mass * radius * radius;
    Ic(1, 1) = Ic(2, 2) = mass * (3 * radius * radius + length * length) / 12.0;
    model.inertial.segment<10>(10 * k) = inertialFromCom(mass, {length / 2, 0, 0}, Ic);
  }
  model.tool = trans(length, 0, 0);
  model.validate();
  return model;
}

}  // namespace mindyn
