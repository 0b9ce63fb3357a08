#include "mindyn/urdf.hpp"

#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <system_error>
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

// ---------------------------------------------------------------------------------------------
// The numbers of a URDF, checked on the XML before urdfdom reads it. urdfdom 3 logs a number it
// cannot read inside a link's <inertial> ("3.7.0", "3,7", "nan", "1e400", " 1.0 "), and a
// missing <mass>, <inertia> or inertia attribute, and then keeps the link with what it had read
// so far: mass and inertia 0. It takes a misspelt attribute (<inertia ixxx=...>, <origin xyx=...>,
// <axis xzy=...>, <limit lowr=...>) as absent, i.e. as its default, and reads only the first of
// two <inertial>, <mass> or <origin> elements. So every number the model takes from a <link> or
// a <joint> is read here first, from the same XML parser (TinyXML, urdfdom 3's), and each
// problem is refused in one line naming the file, line, link or joint, attribute and value.
// ---------------------------------------------------------------------------------------------

/// `c` in lower case (ASCII letters only).
char lowerAscii(char c) { return c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c; }

/// XML's white space (production S of XML 1.0).
bool isXmlSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

bool isDigit(char c) { return c >= '0' && c <= '9'; }

/// Reads `text` (no surrounding white space) as a decimal number: XML Schema's xs:double
/// without INF and NaN (an optional sign, digits with an optional point, an optional exponent),
/// as urdfdom's reader takes it. A value too small for a double rounds to 0. Returns why it is
/// not one ("" when *out is set).
std::string readDecimal(const std::string& text, double* out) {
  const size_t n = text.size();
  size_t i = (n > 0 && (text[0] == '+' || text[0] == '-')) ? 1 : 0;
  const size_t mantissa = i;
  size_t digits = 0;
  while (i < n && isDigit(text[i])) ++i, ++digits;
  const size_t point = i;  // where the point is, or would be
  if (i < n && text[i] == '.') {
    ++i;
    while (i < n && isDigit(text[i])) ++i, ++digits;
  }
  const size_t mantissa_end = i;
  long exponent = 0;
  bool ok = digits > 0;
  if (ok && i < n && (text[i] == 'e' || text[i] == 'E')) {
    ++i;
    const bool negative = i < n && text[i] == '-';
    if (i < n && (text[i] == '+' || text[i] == '-')) ++i;
    size_t exponent_digits = 0;
    for (; i < n && isDigit(text[i]); ++i, ++exponent_digits)
      exponent = std::min(exponent * 10 + (text[i] - '0'), 1000000L);
    ok = exponent_digits > 0;
    if (negative) exponent = -exponent;
  }
  if (!ok || i != n) {
    std::string word;
    for (size_t k = mantissa; k < n; ++k) word += lowerAscii(text[k]);
    if (word == "nan" || word == "inf" || word == "infinity") return "not a finite number";
    return "not a number";
  }
  const char* first = text.data() + (text[0] == '+' ? 1 : 0);
  double value = 0.0;
  const auto [end, error] = std::from_chars(first, text.data() + n, value);
  if (error == std::errc::result_out_of_range) {
    // Out of range: too large if its first significant digit stands at a positive power of ten.
    for (size_t k = mantissa; k < mantissa_end; ++k) {
      if (text[k] == '.' || text[k] == '0') continue;
      const long power =
          k < point ? static_cast<long>(point - k) - 1 : -static_cast<long>(k - point);
      if (power + exponent > 0) return "too large for a double";
      break;
    }
    value = text[0] == '-' ? -0.0 : 0.0;
  } else if (error != std::errc() || end != text.data() + n) {
    return "not a number";
  }
  *out = value;
  return "";
}

/// The number of edits (insertions, deletions, substitutions, swaps of neighbours) from `a` to
/// `b`, case ignored.
size_t editDistance(const std::string& a, const std::string& b) {
  const auto lower = lowerAscii;
  std::vector<std::vector<size_t>> d(a.size() + 1, std::vector<size_t>(b.size() + 1));
  for (size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (size_t i = 1; i <= a.size(); ++i)
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t cost = lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) &&
          lower(a[i - 2]) == lower(b[j - 1]))
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

/// The name of `known` that `name` (not one of them) looks like a misspelling of: one edit from
/// a name of up to 5 letters, two from a longer one; "" if none.
std::string misspelt(const std::string& name, const std::vector<std::string>& known) {
  for (const std::string& k : known) {
    const size_t allowed = k.size() <= 5 ? 1 : 2;
    if (std::max(name.size(), k.size()) - std::min(name.size(), k.size()) > allowed) continue;
    if (editDistance(name, k) <= allowed) return k;
  }
  return "";
}

std::string listNames(const std::vector<std::string>& names) {
  std::string s;
  for (size_t i = 0; i < names.size(); ++i)
    s += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + names[i];
  return s;
}

/// An attribute the model may read: `size` numbers (1 or 3), or text (0).
struct AttributeSpec {
  std::string name;
  int size;
  bool required;
};

/// An element whose attributes the model may read. `strict`: any other attribute is refused;
/// otherwise only one that looks like a misspelling of these (extensions such as <limit
/// current=...> stay allowed).
struct ElementSpec {
  std::vector<AttributeSpec> attributes;
  bool strict;
};

const ElementSpec& originSpec() {
  static const ElementSpec spec{{{"xyz", 3, false}, {"rpy", 3, false}}, true};
  return spec;
}

/// The child elements of <joint> urdfdom reads (each at most once) and what they hold.
const std::map<std::string, ElementSpec>& jointSpecs() {
  static const std::map<std::string, ElementSpec> specs{
      {"origin", originSpec()},
      {"parent", {{{"link", 0, false}}, false}},
      {"child", {{{"link", 0, false}}, false}},
      {"axis", {{{"xyz", 3, true}}, true}},
      {"limit",
       {{{"lower", 1, false}, {"upper", 1, false}, {"effort", 1, true}, {"velocity", 1, true}},
        false}},
      {"dynamics", {{{"damping", 1, false}, {"friction", 1, false}}, false}},
      {"mimic", {{{"joint", 0, true}, {"multiplier", 1, false}, {"offset", 1, false}}, false}},
      {"safety_controller",
       {{{"soft_lower_limit", 1, false},
         {"soft_upper_limit", 1, false},
         {"k_position", 1, false},
         {"k_velocity", 1, true}},
        false}},
      {"calibration", {{{"rising", 1, false}, {"falling", 1, false}}, false}},
  };
  return specs;
}

/// Checks the links and joints of a URDF document; see above.
class NumberCheck {
 public:
  explicit NumberCheck(std::string source) : source_(std::move(source)) {}

  /// Elements that every URDF parser ignores, as "joint 'j1': a second <origin> (line 9)".
  std::vector<std::string> ignored;

  /// Checks the <link> and <joint> elements of `robot` (as urdfdom reads them: the children of
  /// the first <robot>). Numbers written with white space around them or between them other
  /// than single spaces are rewritten in the document; returns true if any was.
  bool run(TiXmlElement* robot) {
    for (TiXmlElement* e = robot->FirstChildElement(); e; e = e->NextSiblingElement()) {
      if (e->ValueStr() == "link") checkLink(e);
      if (e->ValueStr() == "joint") checkJoint(e);
    }
    return rewritten_;
  }

 private:
  [[noreturn]] void fail(const TiXmlElement* at, const std::string& what) const {
    throw ModelError(source_ + ":" + std::to_string(at->Row()) + ": " + owner_ + ": " + what);
  }

  static std::string quote(const std::string& value) {
    constexpr size_t kShown = 40;
    if (value.size() <= kShown) return "\"" + value + "\"";
    return "\"" + value.substr(0, kShown) + "...\"";
  }

  /// `<inertial><mass value="3.7.0">`: the element and one of its attributes, as written.
  std::string show(const TiXmlElement* e, const std::string& attribute,
                   const std::string& value) const {
    return "<" + prefix_ + e->ValueStr() + " " + attribute + "=" + quote(value) + ">";
  }

  void checkLink(TiXmlElement* link) {
    const char* name = link->Attribute("name");
    owner_ = name ? std::string("link '") + name + "'" : "a link without a name";
    prefix_.clear();
    checkChildren(link, {"inertial", "visual", "collision"}, {"inertial"});
    TiXmlElement* inertial = link->FirstChildElement("inertial");
    if (!inertial) return;  // allowed: a massless link, said in Model::notes
    if (const TiXmlAttribute* a = inertial->FirstAttribute())
      fail(inertial,
           "<inertial> has an attribute " + std::string(a->Name()) + "=" + quote(a->ValueStr()) +
               ", which URDF does not define; its values go in the child elements "
               "<origin xyz=\"...\" rpy=\"...\"/>, <mass value=\"...\"/> and <inertia "
               "ixx=\"...\" ixy=\"...\" ixz=\"...\" iyy=\"...\" iyz=\"...\" izz=\"...\"/>");
    const std::vector<std::string> parts{"origin", "mass", "inertia"};
    for (const TiXmlElement* c = inertial->FirstChildElement(); c; c = c->NextSiblingElement())
      if (std::find(parts.begin(), parts.end(), c->ValueStr()) == parts.end())
        fail(c, "<inertial> holds an element <" + c->ValueStr() +
                    ">, which URDF does not define "
                    "there (it holds <origin>, <mass> and <inertia>)");
    checkChildren(inertial, parts, parts);
    prefix_ = "inertial><";
    if (TiXmlElement* o = inertial->FirstChildElement("origin")) checkElement(o, originSpec());
    TiXmlElement* mass = inertial->FirstChildElement("mass");
    if (!mass) fail(inertial, "<inertial> has no <mass value=\"...\"/>");
    checkElement(mass, {{{"value", 1, true}}, true});
    double m = 0.0;
    readDecimal(mass->Attribute("value"), &m);
    if (m < 0.0)
      fail(mass, show(mass, "value", mass->Attribute("value")) + ": a mass cannot be negative");
    TiXmlElement* inertia = inertial->FirstChildElement("inertia");
    if (!inertia)
      fail(inertial,
           "<inertial> has no <inertia ixx=\"...\" ixy=\"...\" ixz=\"...\" iyy=\"...\" "
           "iyz=\"...\" izz=\"...\"/>");
    ElementSpec spec{{}, true};
    for (const char* a : {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"})
      spec.attributes.push_back({a, 1, true});
    checkElement(inertia, spec);
  }

  void checkJoint(TiXmlElement* joint) {
    const char* name = joint->Attribute("name");
    owner_ = name ? std::string("joint '") + name + "'" : "a joint without a name";
    prefix_.clear();
    std::vector<std::string> known;
    for (const auto& kv : jointSpecs()) known.push_back(kv.first);
    checkChildren(joint, known, known);
    const char* type = joint->Attribute("type");
    const bool has_axis =
        !type || (std::string(type) != "fixed" && std::string(type) != "floating");
    for (const auto& [element, spec] : jointSpecs()) {
      TiXmlElement* e = joint->FirstChildElement(element);
      if (!e || (element == "axis" && !has_axis)) continue;  // urdfdom ignores such an axis
      checkElement(e, spec);
      if (element == "dynamics" && !e->Attribute("damping") && !e->Attribute("friction"))
        fail(e, "<dynamics> has neither damping nor friction");
      if (element == "dynamics")
        for (const char* a : {"damping", "friction"}) {
          double v = 0.0;
          if (e->Attribute(a) && readDecimal(e->Attribute(a), &v).empty() && v < 0.0)
            fail(e, show(e, a, e->Attribute(a)) + ": friction cannot be negative");
        }
      if (element == "limit")
        for (const char* a : {"effort", "velocity"}) {
          double v = 0.0;
          readDecimal(e->Attribute(a), &v);
          if (v < 0.0)
            fail(e, show(e, a, e->Attribute(a)) + ": a limit on the magnitude cannot be negative");
        }
    }
  }

  /// Refuses a child element of `parent` whose name looks like a misspelling of one of `known`;
  /// a second one of `unique` goes to `ignored` (urdfdom, and so Pinocchio and ROS, read the
  /// first only, which published descriptions rely on).
  void checkChildren(const TiXmlElement* parent, const std::vector<std::string>& known,
                     const std::vector<std::string>& unique) {
    std::set<std::string> seen;
    for (const TiXmlElement* c = parent->FirstChildElement(); c; c = c->NextSiblingElement()) {
      const std::string& tag = c->ValueStr();
      if (std::find(known.begin(), known.end(), tag) == known.end()) {
        const std::string like = misspelt(tag, known);
        if (!like.empty())
          fail(c, "<" + parent->ValueStr() + "> holds an element <" + tag +
                      ">, which URDF does not define; is it <" + like + ">?");
      } else if (std::find(unique.begin(), unique.end(), tag) != unique.end() &&
                 !seen.insert(tag).second) {
        ignored.push_back(owner_ + ": a second <" + tag + "> (line " + std::to_string(c->Row()) +
                          ")");
      }
    }
  }

  /// Checks the attributes of `e` against `spec`, rewriting numbers to the form urdfdom reads.
  void checkElement(TiXmlElement* e, const ElementSpec& spec) {
    std::vector<std::string> names;
    for (const AttributeSpec& a : spec.attributes) names.push_back(a.name);
    for (const TiXmlAttribute* a = e->FirstAttribute(); a; a = a->Next()) {
      const std::string name = a->Name();
      if (std::find(names.begin(), names.end(), name) != names.end()) continue;
      const std::string like = misspelt(name, names);
      if (!spec.strict && like.empty()) continue;
      fail(e, "<" + prefix_ + e->ValueStr() + "> has an attribute " + name + "=" +
                  quote(a->ValueStr()) + ", which URDF does not define there" +
                  (like.empty() ? "" : "; is it " + like + "?") + " (it takes " + listNames(names) +
                  ")");
    }
    for (const AttributeSpec& spec_a : spec.attributes) {
      const char* raw = e->Attribute(spec_a.name.c_str());
      if (!raw) {
        if (spec_a.required)
          fail(e, "<" + prefix_ + e->ValueStr() + "> has no attribute " + spec_a.name +
                      " (it needs " + listNames(requiredNames(spec)) + ")");
        continue;
      }
      if (spec_a.size == 0) continue;
      const std::string value = raw;
      std::vector<std::string> pieces;
      std::string piece;
      for (char c : value + ' ') {
        if (!isXmlSpace(c)) {
          piece += c;
        } else if (!piece.empty()) {
          pieces.push_back(piece);
          piece.clear();
        }
      }
      const std::string shown = show(e, spec_a.name, value);
      if (static_cast<int>(pieces.size()) != spec_a.size)
        fail(e, shown + ": " +
                    (spec_a.size == 1 ? std::string("expected one number") : "expected 3 numbers") +
                    ", got " +
                    (pieces.empty() ? std::string("none") : std::to_string(pieces.size())));
      std::string canonical;
      for (const std::string& p : pieces) {
        double v = 0.0;
        const std::string why = readDecimal(p, &v);
        const std::string which = spec_a.size == 1 ? "" : quote(p) + " ";
        if (why == "too large for a double" || (why.empty() && std::abs(v) > kMaxDescriptionValue))
          fail(e, shown + ": " + which + "exceeds the bound " + formatBound() +
                      " on the magnitude of a description value");
        if (!why.empty()) fail(e, shown + ": " + (spec_a.size == 1 ? why : which + "is " + why));
        canonical += (canonical.empty() ? "" : " ") + p;
      }
      if (canonical != value) {
        e->SetAttribute(spec_a.name.c_str(), canonical.c_str());
        rewritten_ = true;
      }
    }
  }

  static std::vector<std::string> requiredNames(const ElementSpec& spec) {
    std::vector<std::string> names;
    for (const AttributeSpec& a : spec.attributes)
      if (a.required) names.push_back(a.name);
    return names;
  }

  static std::string formatBound() {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", kMaxDescriptionValue);
    return buf;
  }

  const std::string source_;
  std::string owner_;   // "link 'l1'" or "joint 'j1'"
  std::string prefix_;  // "inertial><" inside <inertial>
  bool rewritten_ = false;
};

// ---------------------------------------------------------------------------------------------
// Transmissions as ros_control writes them, read from the same XML: ROS 1 <transmission> children
// of <robot> (<type>, <joint name><role><offset><mechanicalReduction>, <actuator name><role>
// <mechanicalReduction>) and ROS 2 <ros2_control><transmission name> (<plugin>, <actuator name
// role><mechanical_reduction>, <joint name role><offset><mechanical_reduction>); either spelling
// of the reduction is read in either form. PR2's older form, <transmission name type> in
// <robot> (its type in the type attribute, or in <type> as pr2_mechanism_model reads it too),
// of pr2_mechanism_model's SimpleTransmission (<actuator name>, <joint name>,
// <mechanicalReduction>) and WristTransmission (<rightActuator>, <leftActuator>, <flexJoint>,
// <rollJoint>, each with name and mechanicalReduction attributes), goes with either form
// (alone it counts as the ROS 1 form); the names without "pr2_mechanism_model/", which it once
// resolved, are read from the type attribute. Transmissions of other types (PR2's belt compensator
// and gripper, a SimpleTransmission with PR2's <simulated_actuated_joint>, other plugins) are left
// out and kept in Model::unread_transmissions; one naming no joint of the file is left out and
// named in the notes. Each problem of the types read is refused in one line naming the file, line,
// transmission and element.
// ---------------------------------------------------------------------------------------------

class TransmissionReader {
 public:
  explicit TransmissionReader(std::string source) : source_(std::move(source)) {}

  /// The transmissions declared under `robot`; `format` is set to "ros1" or "ros2" (a file
  /// mixing both forms is refused; PR2's form goes with either, and alone is "ros1").
  std::vector<TransmissionGroup> run(const TiXmlElement* robot, std::string* format) {
    std::vector<TransmissionGroup> groups;
    for (const TiXmlElement* e = robot->FirstChildElement(); e; e = e->NextSiblingElement()) {
      if (e->ValueStr() == "transmission") {
        const std::string pr2 = pr2Type(e);
        if (!pr2.empty()) {  // beside either form (files ported to ROS 2 may keep PR2's)
          groups.push_back(readPr2(e, pr2));
          continue;
        }
        if (other(e, false)) continue;
        setFormat(e, "ros1", format);
        groups.push_back(read(e, false));
      } else if (e->ValueStr() == "ros2_control") {
        for (const TiXmlElement* t = e->FirstChildElement("transmission"); t;
             t = t->NextSiblingElement("transmission")) {
          if (other(t, true)) continue;
          setFormat(t, "ros2", format);
          groups.push_back(read(t, true));
        }
      }
    }
    if (format->empty() && !groups.empty()) *format = "ros1";  // PR2's form alone
    std::set<std::string> names, actuators;
    for (const TransmissionGroup& g : groups) {
      if (!names.insert(g.name).second)
        throw ModelError(source_ + ":" + std::to_string(g.line) + ": transmission '" + g.name +
                         "' is declared twice");
      for (const std::string& a : g.actuators)
        if (!actuators.insert(a).second)
          throw ModelError(source_ + ":" + std::to_string(g.line) + ": transmission '" + g.name +
                           "': actuator '" + a + "' belongs to another transmission too");
    }
    return groups;
  }

  /// Transmissions of other types (PR2's belt compensator and gripper, other plugins such as
  /// HalfDifferentialTransmission), left out: name, type as written, the joints it names (each
  /// child element whose tag ends in "joint" or "Joint": <joint>, PR2's <gap_joint>,
  /// <passive_joint>, <simulated_actuated_joint>) and its line.
  std::vector<TransmissionGroup> skipped;

 private:
  /// The type of transmission `t` as written: its <type> (ROS 2: <plugin>) element, else (ROS 1)
  /// its type attribute (PR2's form); `attribute` tells which.
  static std::string typeOf(const TiXmlElement* t, bool ros2, bool* attribute = nullptr) {
    const TiXmlElement* type = t->FirstChildElement(ros2 ? "plugin" : "type");
    const bool from_attribute = !type && !ros2 && t->Attribute("type");
    if (attribute) *attribute = from_attribute;
    if (from_attribute) return t->Attribute("type");
    return type ? trimmed(type->GetText()) : "";
  }

  /// PR2's names of the types read from its form, and the same without the package, which
  /// pr2_mechanism_model once resolved and reads from the type attribute only.
  static const std::vector<std::string>& pr2Names(bool attribute) {
    static const std::vector<std::string> full{kPr2Simple, kPr2Wrist};
    static const std::vector<std::string> both{kPr2Simple, kPr2Wrist, "SimpleTransmission",
                                               "WristTransmission"};
    return attribute ? both : full;
  }

  /// The type as written when ROS 1 transmission `t` is one of PR2's types read here (or looks
  /// like a misspelling of one, which readPr2 refuses), else "". A SimpleTransmission with a
  /// <simulated_actuated_joint> (whose effort goes to that joint in PR2's simulator) is no
  /// linear map of its joints: "", left to other().
  static std::string pr2Type(const TiXmlElement* t) {
    bool attribute = false;
    const std::string full = typeOf(t, false, &attribute);
    const std::vector<std::string>& names = pr2Names(attribute);
    const bool known = std::find(names.begin(), names.end(), full) != names.end();
    if (full.empty() || (!known && misspelt(full, names).empty())) return "";
    if (known && full.find("SimpleTransmission") != std::string::npos &&
        t->FirstChildElement("simulated_actuated_joint"))
      return "";
    return full;
  }

  /// True (and noted in `skipped`) for a transmission of a type that is none of those read
  /// here nor looks like a misspelling of one of ros_control's. Such transmissions are not
  /// read.
  bool other(const TiXmlElement* t, bool ros2) {
    const std::string full = typeOf(t, ros2);
    const std::vector<std::string> known{"transmission_interface/SimpleTransmission",
                                         "transmission_interface/DifferentialTransmission",
                                         "transmission_interface/FourBarLinkageTransmission"};
    if (full.empty() || std::find(known.begin(), known.end(), full) != known.end() ||
        !misspelt(full, known).empty())
      return false;  // read (or refused as a misspelling)
    TransmissionGroup g;
    const char* name = t->Attribute("name");
    g.name = name ? name : "";
    g.type = full;
    g.line = t->Row();
    for (const TiXmlElement* j = t->FirstChildElement(); j; j = j->NextSiblingElement()) {
      const std::string& tag = j->ValueStr();
      const bool joint = tag.size() >= 5 && (tag.compare(tag.size() - 5, 5, "joint") == 0 ||
                                             tag.compare(tag.size() - 5, 5, "Joint") == 0);
      if (const char* jn = j->Attribute("name"); joint && jn) g.joints.emplace_back(jn);
    }
    skipped.push_back(g);
    return true;
  }

  void setFormat(const TiXmlElement* e, const std::string& form, std::string* format) const {
    if (!format->empty() && *format != form)
      throw ModelError(source_ + ":" + std::to_string(e->Row()) +
                       ": transmissions in both the ROS 1 form (<transmission> in <robot>) and "
                       "the ROS 2 form (in <ros2_control>); use one");
    *format = form;
  }

  [[noreturn]] void fail(const TiXmlElement* at, const std::string& what) const {
    throw ModelError(source_ + ":" + std::to_string(at->Row()) + ": " + owner_ + ": " + what);
  }

  static std::string trimmed(const char* text) {
    std::string s = text ? text : "";
    size_t b = 0, e = s.size();
    while (b < e && isXmlSpace(s[b])) ++b;
    while (e > b && isXmlSpace(s[e - 1])) --e;
    return s.substr(b, e - b);
  }

  /// The only child <tag> of `e` (nullptr if none; a second one is refused), after refusing a
  /// child that looks like a misspelling of one of `known`.
  const TiXmlElement* only(const TiXmlElement* e, const std::string& tag,
                           const std::vector<std::string>& known) const {
    for (const TiXmlElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) {
      const std::string& t = c->ValueStr();
      if (std::find(known.begin(), known.end(), t) != known.end()) continue;
      const std::string like = misspelt(t, known);
      if (!like.empty())
        fail(c, "<" + e->ValueStr() + "> holds an element <" + t + ">, which " + definer_ +
                    " does not define in this form; is it <" + like + ">?");
    }
    const TiXmlElement* found = e->FirstChildElement(tag);
    if (found && found->NextSiblingElement(tag))
      fail(found->NextSiblingElement(tag), "<" + e->ValueStr() + "> holds a second <" + tag + ">");
    return found;
  }

  /// The number written in element `c` (child of <where>); a non-zero one if `nonzero`.
  double number(const TiXmlElement* c, const std::string& where, bool nonzero) const {
    const std::string text = trimmed(c->GetText());
    return parsed(c, text,
                  "<" + where + "><" + c->ValueStr() + ">" + text + "</" + c->ValueStr() + ">",
                  nonzero);
  }

  /// The number `text` (shown as `shown` in a refusal of element `at`); non-zero if `nonzero`.
  double parsed(const TiXmlElement* at, const std::string& text, const std::string& shown,
                bool nonzero) const {
    if (text.empty()) fail(at, shown + ": expected a number, got none");
    double v = 0.0;
    const std::string why = readDecimal(text, &v);
    if (why == "too large for a double" || (why.empty() && std::abs(v) > kMaxDescriptionValue))
      fail(at, shown + ": exceeds the bound on the magnitude of a description value");
    if (!why.empty()) fail(at, shown + ": " + why);
    if (nonzero && v == 0.0) fail(at, shown + ": a reduction cannot be zero");
    return v;
  }

  struct Member {
    const TiXmlElement* element;
    std::string name;
    int role;  // 0-based, -1 if none given
    double reduction;
    bool has_reduction;
    double offset;
    bool has_offset;
  };

  /// A group of `t` with its name and line (refused without a name); sets owner_ and
  /// definer_.
  TransmissionGroup named(const TiXmlElement* t, const std::string& definer) {
    TransmissionGroup g;
    g.line = t->Row();
    definer_ = definer;
    const char* name = t->Attribute("name");
    if (!name || !*name) {
      owner_ = "a transmission";
      fail(t, "<transmission> has no name attribute");
    }
    g.name = name;
    owner_ = "transmission '" + g.name + "'";
    return g;
  }

  /// PR2's form (pr2_mechanism_model), type `written` as pr2Type found it.
  TransmissionGroup readPr2(const TiXmlElement* t, const std::string& written) {
    TransmissionGroup g = named(t, "pr2_mechanism_model");
    const bool wrist = written.find("WristTransmission") != std::string::npos;
    g.type = wrist ? kPr2Wrist : kPr2Simple;
    bool attribute = false;
    typeOf(t, false, &attribute);
    const std::vector<std::string>& names = pr2Names(attribute);
    if (std::find(names.begin(), names.end(), written) == names.end())
      fail(t, "type '" + written + "': is it " + misspelt(written, names) + "?");
    const std::string kind =
        "PR2's " + std::string(wrist ? "WristTransmission" : "SimpleTransmission");
    if (!wrist) {
      const std::vector<std::string> known{"type", "joint", "actuator", "mechanicalReduction"};
      const TiXmlElement* joint = only(t, "joint", known);
      const TiXmlElement* actuator = only(t, "actuator", known);
      const TiXmlElement* reduction = only(t, "mechanicalReduction", known);
      for (const TiXmlElement* m : {joint, actuator})
        for (const char* tag : {"mechanicalReduction", "mechanical_reduction"})
          if (const TiXmlElement* inner = m ? m->FirstChildElement(tag) : nullptr)
            fail(inner, "<" + m->ValueStr() + "> holds a <" + tag + ">; " + kind +
                            " reads the reduction from <mechanicalReduction> in <transmission>");
      if (!joint) fail(t, kind + " needs a <joint name=...>");
      if (!actuator) fail(t, kind + " needs an <actuator name=...>");
      if (!reduction) fail(t, kind + " needs a <mechanicalReduction> in <transmission>");
      g.joints.push_back(nameOf(joint));
      g.actuators.push_back(nameOf(actuator));
      g.actuator_reduction.push_back(number(reduction, "transmission", true));
      g.joint_reduction.push_back(1.0);
      g.joint_offset.push_back(0.0);
      return g;
    }
    const std::vector<std::string> known{"type", "rightActuator", "leftActuator", "flexJoint",
                                         "rollJoint"};
    for (const char* tag : {"rightActuator", "leftActuator", "flexJoint", "rollJoint"}) {
      const TiXmlElement* e = only(t, tag, known);
      if (!e)
        fail(t, kind + " needs a <" + std::string(tag) + " name=... mechanicalReduction=...>");
      const std::string name = nameOf(e);
      const char* value = e->Attribute("mechanicalReduction");
      const std::string shown = "<" + e->ValueStr() + " name=\"" + name + "\">";
      if (!value) fail(e, shown + " has no mechanicalReduction attribute");
      const double r = parsed(e, trimmed(value),
                              shown + " mechanicalReduction=\"" + std::string(value) + "\"", true);
      const bool actuator = e->ValueStr().find("Actuator") != std::string::npos;
      (actuator ? g.actuators : g.joints).push_back(name);
      (actuator ? g.actuator_reduction : g.joint_reduction).push_back(r);
    }
    g.joint_offset = {0.0, 0.0};
    if (g.actuators[0] == g.actuators[1])
      fail(t, "<rightActuator> and <leftActuator> both name '" + g.actuators[0] + "'");
    if (g.joints[0] == g.joints[1])
      fail(t, "<flexJoint> and <rollJoint> both name '" + g.joints[0] + "'");
    return g;
  }

  /// The name attribute of element `e`, refused when missing or empty.
  std::string nameOf(const TiXmlElement* e) const {
    const char* name = e->Attribute("name");
    if (!name || !*name) fail(e, "<" + e->ValueStr() + "> has no name attribute");
    return name;
  }

  TransmissionGroup read(const TiXmlElement* t, bool ros2) {
    TransmissionGroup g = named(t, "ros_control");
    const std::string type_tag = ros2 ? "plugin" : "type";
    const std::string reduction_tag = ros2 ? "mechanical_reduction" : "mechanicalReduction";
    const std::vector<std::string> known{type_tag, "joint", "actuator"};
    const TiXmlElement* type = only(t, type_tag, known);
    const std::string kTypes =
        "transmission_interface/SimpleTransmission, DifferentialTransmission or "
        "FourBarLinkageTransmission";
    if (!type) fail(t, "<transmission> has no <" + type_tag + "> (" + kTypes + ")");
    const std::string full = trimmed(type->GetText());
    const std::string prefix = "transmission_interface/";
    g.type = full.rfind(prefix, 0) == 0 ? full.substr(prefix.size()) : "";
    if (g.type != "SimpleTransmission" && g.type != "DifferentialTransmission" &&
        g.type != "FourBarLinkageTransmission")
      fail(type, "<" + type_tag + ">" + full + "</" + type_tag + ">: is it " +
                     misspelt(full, {"transmission_interface/SimpleTransmission",
                                     "transmission_interface/DifferentialTransmission",
                                     "transmission_interface/FourBarLinkageTransmission"}) +
                     "?");
    const size_t count = g.type == "SimpleTransmission" ? 1 : 2;
    const std::vector<Member> joints = members(t, "joint", count, ros2, reduction_tag);
    const std::vector<Member> actuators = members(t, "actuator", count, ros2, reduction_tag);
    for (const Member& a : actuators) {
      if (!ros2 && !a.has_reduction)
        fail(a.element, "<actuator name=\"" + a.name + "\"> has no <" + reduction_tag + ">");
      if (a.has_offset)
        fail(a.element, "<actuator name=\"" + a.name +
                            "\"> has an <offset>; "
                            "ros_control gives offsets to joints");
      if (ros2 && count == 1 && a.has_reduction)
        fail(a.element, "<actuator name=\"" + a.name + "\"> has a <" + reduction_tag +
                            ">; ros2_control's SimpleTransmission reads it from <joint>");
      g.actuators.push_back(a.name);
      g.actuator_reduction.push_back(a.has_reduction ? a.reduction : 1.0);
    }
    for (const Member& j : joints) {
      if (!ros2 && count == 1 && j.has_reduction)
        fail(j.element, "<joint name=\"" + j.name + "\"> has a <" + reduction_tag +
                            ">; ros_control's SimpleTransmission reads it from <actuator>");
      g.joints.push_back(j.name);
      g.joint_reduction.push_back(j.has_reduction ? j.reduction : 1.0);
      g.joint_offset.push_back(j.has_offset ? j.offset : 0.0);
    }
    if (ros2 && count == 1) {  // the reduction is the joint's; keep it as the actuator's
      g.actuator_reduction[0] = g.joint_reduction[0];
      g.joint_reduction[0] = 1.0;
    }
    return g;
  }

  /// The `count` <joint> or <actuator> children of transmission `t`, ordered by role.
  std::vector<Member> members(const TiXmlElement* t, const std::string& kind, size_t count,
                              bool ros2, const std::string& reduction_tag) const {
    std::vector<Member> found;
    for (const TiXmlElement* e = t->FirstChildElement(kind); e; e = e->NextSiblingElement(kind)) {
      Member m{e, "", -1, 1.0, false, 0.0, false};
      const char* name = e->Attribute("name");
      if (!name || !*name) fail(e, "<" + kind + "> has no name attribute");
      m.name = name;
      const std::string where = kind + " name=\"" + m.name + "\"";
      // The other form's spelling is read too (files mix them), but not both at once.
      const std::string other_tag = ros2 ? "mechanicalReduction" : "mechanical_reduction";
      std::vector<std::string> known{reduction_tag, other_tag, "offset", "hardwareInterface"};
      if (!ros2) known.push_back("role");
      const TiXmlElement* role_e = ros2 ? nullptr : only(e, "role", known);
      const char* role_a = ros2 ? e->Attribute("role") : nullptr;
      if (role_e || role_a) {
        const std::string role = role_e ? trimmed(role_e->GetText()) : trimmed(role_a);
        for (size_t r = 0; r < count; ++r)
          if (role == kind + std::to_string(r + 1)) m.role = static_cast<int>(r);
        if (m.role < 0 && count > 1)
          fail(role_e ? role_e : e,
               "<" + where + ">: role '" + role + "' is not " + kind + "1 or " + kind + "2");
      } else if (count > 1 && !ros2) {
        fail(e, "<" + where + "> has no <role> (" + kind + "1 or " + kind + "2)");
      }
      const TiXmlElement* r = only(e, reduction_tag, known);
      const TiXmlElement* r2 = only(e, other_tag, known);
      if (r && r2)
        fail(r2, "<" + where + "> holds both <" + reduction_tag + "> and <" + other_tag +
                     ">; give one");
      if (!r) r = r2;
      if (r) {
        m.reduction = number(r, where, true);
        m.has_reduction = true;
      }
      if (const TiXmlElement* o = only(e, "offset", known)) {
        m.offset = number(o, where, false);
        m.has_offset = true;
      }
      found.push_back(m);
    }
    if (found.size() != count)
      fail(t, "a " + std::string(count == 1 ? "SimpleTransmission" : "two-joint transmission") +
                  " needs " + std::to_string(count) + " <" + kind + "> element" +
                  (count > 1 ? "s" : "") + ", found " + std::to_string(found.size()));
    if (count > 1) {
      const bool roles = found[0].role >= 0 || found[1].role >= 0;
      if (roles && (found[0].role < 0 || found[1].role < 0))
        fail(found[found[0].role < 0 ? 0 : 1].element,
             "<" + kind + "> has no role while the other has one");
      if (roles && found[0].role == found[1].role)
        fail(found[1].element, "two <" + kind + "> elements have the role " + kind +
                                   std::to_string(found[0].role + 1));
      if (roles && found[0].role == 1) std::swap(found[0], found[1]);
      if (found[0].name == found[1].name)
        fail(found[1].element, "both <" + kind + "> elements name '" + found[0].name + "'");
    }
    return found;
  }

  const std::string source_;
  std::string owner_;
  std::string definer_ = "ros_control";  // whose form is being read, for refusals
};

/// The URDF text urdfdom is to read: `xml` once its links and joints passed NumberCheck, with
/// numbers written with extra white space rewritten. Text TinyXML cannot parse is returned as
/// it is, for urdfdom to report.
/// The transmissions are read into `groups` and `format`; those of other types go to
/// `skipped` (not read: name, type, joints), and elements every URDF parser ignores to
/// `ignored`.
std::string checkNumbers(const std::string& xml, const std::string& source,
                         std::vector<TransmissionGroup>* groups, std::string* format,
                         std::vector<TransmissionGroup>* skipped,
                         std::vector<std::string>* ignored) {
  TiXmlDocument doc;
  doc.Parse(xml.c_str());
  TiXmlElement* robot = doc.Error() ? nullptr : doc.FirstChildElement("robot");
  if (robot) {
    TransmissionReader reader(source);
    *groups = reader.run(robot, format);
    *skipped = reader.skipped;
  }
  if (!robot) return xml;
  NumberCheck check(source);
  const bool rewritten = check.run(robot);
  *ignored = check.ignored;
  if (!rewritten) return xml;
  TiXmlPrinter printer;
  doc.Accept(&printer);
  return printer.Str();
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
  Builder(const urdf::ModelInterface& urdf, std::string source, std::string root_joint)
      : urdf_(urdf), source_(std::move(source)), root_joint_(std::move(root_joint)) {}

  Model build(const std::string& tip_name) {
    root_ = urdf_.getRoot();
    if (!root_) fail("has no root link");
    if (!root_joint_.empty() && root_joint_ != "floating" && root_joint_ != "planar")
      throw ModelError("the root joint must be 'floating' or 'planar' (or none), not '" +
                       escapeControl(root_joint_) + "'");
    checkTree();
    if (!tip_name.empty()) return buildChain(findTip(tip_name));
    if (!root_joint_.empty()) return buildTree();
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
    addRootJoint(&model);
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
    addRootJoint(&model);
    if (!model.joints.empty()) model.parents.push_back(-1);
    addSubtree(*root_, model.joints.empty() ? -1 : 0, Eigen::Isometry3d::Identity(), &model);
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
               "avoids it with a tip link (tip=)");
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
    model.link_names.push_back(root_joint_.empty() ? root_->name : std::string("world"));
    return model;
  }

  /// With a root joint requested: the free-flyer or planar joint "root_joint" from the world
  /// to the root link, which becomes the first moving body (with every link rigidly attached
  /// to it).
  void addRootJoint(Model* model) {
    if (root_joint_.empty()) return;
    Joint j;
    j.name = "root_joint";
    j.type = root_joint_ == "floating" ? JointType::FreeFlyer : JointType::Planar;
    viscous_.push_back(0.0);
    coulomb_.push_back(0.0);
    model->joints.push_back(j);
    model->link_names.push_back(root_->name);
    bodies_.push_back(root_.get());
    on_path_.insert(root_->name);
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
    else if (uj.type == urdf::Joint::FLOATING)
      j.type = JointType::FreeFlyer;
    else if (uj.type == urdf::Joint::PLANAR)
      j.type = JointType::Planar;
    else
      fail("joint '" + uj.name + "' has type '" + urdfTypeName(uj.type) +
           "', which is not supported (revolute, continuous, prismatic, floating, planar and "
           "fixed joints are)");
    if (uj.mimic)
      fail("joint '" + uj.name + "' mimics joint '" + uj.mimic->joint_name +
           "', which is not supported; load a chain that ends before it with a tip link "
           "(tip=), e.g. its parent link '" +
           uj.parent_link_name + "', which locks it at q = 0");
    const Eigen::Vector3d axis(uj.axis.x, uj.axis.y, uj.axis.z);
    if (j.type != JointType::FreeFlyer && axis.norm() < 1e-12)  // a floating joint has none
      fail("joint '" + uj.name + "' has a zero or invalid axis");
    j.axis = j.type == JointType::FreeFlyer ? Eigen::Vector3d::UnitZ() : axis.normalized();
    j.pre = pre;
    if (j.type == JointType::Planar) {
      // the motion in the plane normal to <axis>: J in a frame A whose z is the axis,
      // T = pre A J A^T
      const Eigen::Matrix3d A =
          Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), j.axis).toRotationMatrix();
      j.pre.linear() = j.pre.linear() * A;
      j.post.linear() = A.transpose();
      j.axis = Eigen::Vector3d::UnitZ();
    }
    if (uj.limits && j.singleDof()) {
      const urdf::JointLimits& lim = *uj.limits;
      // urdfdom reports absent lower/upper as 0/0 and absent velocity/effort as 0: not given.
      if (uj.type != urdf::Joint::CONTINUOUS && !(lim.lower == 0.0 && lim.upper == 0.0)) {
        j.limits.lower = lim.lower;
        j.limits.upper = lim.upper;
      }
      if (lim.velocity > 0.0) j.limits.velocity = lim.velocity;
      if (lim.effort > 0.0) j.limits.effort = lim.effort;
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
    std::vector<std::string> notes;
    if (!locked_.empty()) notes.push_back(locked + joinNames(locked_));
    if (!massless_.empty())
      notes.push_back("links without <inertial>, taken as massless: " + joinNames(massless_));
    for (const std::string& note : notes) model->notes += (model->notes.empty() ? "" : "; ") + note;
    if (model->isSerial()) model->parents.clear();
    model->validate();
    return std::move(*model);
  }

  [[noreturn]] void fail(const std::string& what) const { throw ModelError(source_ + ": " + what); }

  static Eigen::Isometry3d jointOrigin(const urdf::Joint& j) {
    return toIsometry(j.parent_to_joint_origin_transform);
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
    if (j.limits && j.type != urdf::Joint::CONTINUOUS && j.limits->lower <= j.limits->upper)
      q = std::min(std::max(0.0, j.limits->lower), j.limits->upper);
    const Eigen::Vector3d axis(j.axis.x, j.axis.y, j.axis.z);
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
    if (!link.inertial) {
      massless_.push_back(link.name);
    } else {  // its numbers were checked by NumberCheck
      const urdf::Inertial& in = *link.inertial;
      const Eigen::Isometry3d frame = toIsometry(in.origin);
      Eigen::Matrix3d Ic;
      Ic << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
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
  const std::string root_joint_;
  urdf::LinkConstSharedPtr root_;
  std::set<std::string> on_path_;  // links of the model's moving joints (chain: the whole path)
  std::map<std::string, bool> moving_below_;
  std::vector<std::string> locked_;
  std::vector<std::string> massless_;      // links merged into the model that have no <inertial>
  std::vector<const urdf::Link*> bodies_;  // child links of the model's joints
  std::vector<double> viscous_, coulomb_;
};

/// Sets the model's transmission from the groups read; the URDF's joints that are not moving
/// joints of the model are held at their locked position (fixed: 0; moving: 0 clamped into
/// their limits, as the Builder locks them).
void addTransmissions(const urdf::ModelInterface& urdf,
                      const std::vector<TransmissionGroup>& groups, const std::string& format,
                      Model* model) {
  std::vector<std::string> names, locked;
  std::vector<double> q;
  for (const Joint& j : model->joints) names.push_back(j.name);
  for (const auto& [name, j] : urdf.joints_) {
    if (!j || std::find(names.begin(), names.end(), name) != names.end()) continue;
    double v = 0.0;
    if (isMoving(*j) && j->limits && j->type != urdf::Joint::CONTINUOUS &&
        j->limits->lower <= j->limits->upper)
      v = std::min(std::max(0.0, j->limits->lower), j->limits->upper);
    locked.push_back(name);
    q.push_back(v);
  }
  model->transmission =
      assembleTransmission(groups, format, model->joints, locked, q, model->source, &model->notes);
  model->validate();
}

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

Model parseUrdf(const std::string& xml, const std::string& tip, const std::string& source,
                const std::string& root_joint) {
  try {
    requireUtf8(xml, source);
    std::string reason, format;
    std::vector<TransmissionGroup> groups, skipped;
    std::vector<std::string> ignored;
    const urdf::ModelInterfaceSharedPtr urdf =
        parseQuietly(checkNumbers(xml, source, &groups, &format, &skipped, &ignored), &reason);
    if (!urdf) throw ModelError(source + ": not a valid URDF: " + reason);
    Model model = Builder(*urdf, source, root_joint).build(tip);
    if (!groups.empty()) addTransmissions(*urdf, groups, format, &model);
    model.unread_transmissions = skipped;  // the Python loader warns of them, once
    if (!ignored.empty()) {
      std::string text;
      for (const std::string& k : ignored) text += (text.empty() ? "" : ", ") + k;
      model.notes += (model.notes.empty() ? "" : "; ") +
                     std::string("elements every URDF parser ignores (the first is read): ") + text;
    }
    return model;
  } catch (const ModelError& e) {
    throw ModelError(escapeControl(e.what()));  // names from the file may hold line breaks
  }
}

Model loadUrdf(const std::string& path, const std::string& tip, const std::string& root_joint) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw FileError("URDF file '" + path + "' does not exist");
  if (fs::is_directory(path, ec)) throw FileError("URDF file '" + path + "' is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError("URDF file '" + path + "' cannot be read");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw FileError("URDF file '" + path + "' cannot be read");
  return parseUrdf(text.str(), tip, path, root_joint);
}

}  // namespace mindyn
