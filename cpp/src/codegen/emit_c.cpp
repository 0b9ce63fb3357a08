#include "mindyn/codegen/emit_c.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <unordered_map>

#include "internal.hpp"
#include "mindyn/sincos.hpp"

namespace mindyn::codegen {

std::string literal(double v, bool structured_text) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, res.ptr);
  const size_t e = s.find('e');
  std::string mant = e == std::string::npos ? s : s.substr(0, e);
  std::string expo = e == std::string::npos ? "" : s.substr(e + 1);
  if (mant.find('.') == std::string::npos) mant += ".0";
  if (expo.empty()) return mant;
  return mant + (structured_text ? "E" : "e") + expo;
}

namespace {

std::string wrap(const std::string& text, size_t width, const std::string& indent) {
  std::string out, line;
  std::istringstream in(text);
  std::string word;
  while (in >> word) {
    if (!line.empty() && line.size() + 1 + word.size() > width) {
      out += line + "\n";
      line = indent;
    }
    line += (line.empty() || line == indent ? "" : " ") + word;
  }
  return out + line;
}

}  // namespace

namespace internal {

std::string frictionWords(FrictionKind kind) {
  static const char* const words[] = {
      "viscous and Coulomb friction", "viscous and direction-dependent Coulomb friction",
      "viscous and smooth Coulomb friction", "viscous, Coulomb and Stribeck friction"};
  return words[static_cast<int>(kind)];
}

void openStepHeader(std::ostream& h, const std::string& fn, const std::vector<std::string>& lines,
                    int n, int np) {
  std::string NAME = fn;
  for (char& ch : NAME) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  h << "/*\n";
  for (const auto& l : lines) h << (l.empty() ? " *" : " * " + l) << "\n";
  h << " */\n#ifndef " << NAME << "_H\n#define " << NAME << "_H\n\n";
  h << "#ifdef __cplusplus\nextern \"C\" {\n#endif\n\n";
  h << "#define " << NAME << "_N " << n << "\n#define " << NAME << "_NP " << np << "\n\n";
}

std::vector<std::string> driveLines(const GeneratedCode& code) {
  std::vector<std::string> lines;
  const ParameterLayout& layout = code.params.layout;
  if (!layout.rotor && !layout.friction) return lines;
  const std::string slot = code.motor_side ? "motor" : "joint";
  if (!code.motor_side && !code.motors.empty())
    lines.push_back("Rotor inertia and friction on the joints, not through the transmissions.");
  if (code.motor_side) {
    lines.push_back("Rotor inertia and friction on the " + std::to_string(code.T.rows()) +
                    " motors (slot k of Ia, Fv, Fc is motor k's,");
    lines.push_back(
        "in motor units): tau += T^T (Ia T ddq + friction(T dq)), T's rows (q_m = T q):");
    for (long k = 0; k < code.T.rows(); ++k) {
      std::string row;
      for (long j = 0; j < code.T.cols(); ++j) {
        const double t = code.T(k, j);
        if (t == 0.0) continue;
        const std::string mag = std::abs(t) == 1.0 ? "" : literal(std::abs(t)) + " ";
        row += (row.empty() ? (t < 0 ? "-" : "") : (t < 0 ? " - " : " + ")) + mag + "q" +
               std::to_string(j + 1);
      }
      std::istringstream split(
          wrap(std::to_string(k + 1) + ". " + code.motors[static_cast<size_t>(k)] + " = " + row, 88,
               "    "));
      for (std::string part; std::getline(split, part);) lines.push_back("  " + part);
    }
  }
  if (!layout.friction) return lines;
  static const char* const formula[] = {"Fv v + Fc sign(v)", "Fv v + Fc sign(v) + Fa |sign(v)|",
                                        "Fv v + Fc tanh(v / w)",
                                        "Fv v + Fc sign(v) + Fs sign(v) exp(-(v / w)^2)"};
  static const char* const scale[] = {"", "", "tanh width", "Stribeck velocity"};
  const int kind = static_cast<int>(code.friction.kind);
  lines.push_back("Friction of each " + slot + " at its velocity v (sign(0) = 0):");
  std::string f = formula[kind];
  if (scale[kind][0] != '\0') {
    f += std::string(", w the ") + scale[kind] + " per " + slot + ":";
    for (long k = 0; k < code.friction.velocity.size(); ++k)
      f += (k ? ", " : " ") + literal(code.friction.velocity[k]);
  }
  std::istringstream split(wrap(f + ".", 86, "  "));
  for (std::string part; std::getline(split, part);) lines.push_back("  " + part);
  return lines;
}

}  // namespace internal

namespace {

std::string range(const char* name, int first, int size) {
  return std::string(name) + "[" + std::to_string(first) +
         (size > 1 ? ".." + std::to_string(first + size - 1) : "") + "]";
}

// A floating base: the coordinates of each joint, and the contact wrenches.
std::vector<std::string> floatingLines(const GeneratedCode& code) {
  std::vector<std::string> lines;
  lines.push_back("A floating base: q has " + std::to_string(code.nq) +
                  " entries, dq, ddq and tau " + std::to_string(code.nv) +
                  " (Pinocchio's convention);");
  lines.push_back("each joint's entries, and the joint it is mounted on:");
  int iq = 0, iv = 0;
  for (size_t k = 0; k < code.joints.size(); ++k) {
    const int p = code.parents[k];
    const bool ff = code.kinds[k] == JointType::FreeFlyer,
               planar = code.kinds[k] == JointType::Planar;
    const int nq = ff ? 7 : planar ? 4 : 1, nv = ff ? 6 : planar ? 3 : 1;
    lines.push_back("  " + std::to_string(k + 1) + ". " + code.joints[k] + " (" +
                    toString(code.kinds[k]) + ", on " +
                    (p < 0 ? std::string("the base") : code.joints[static_cast<size_t>(p)]) +
                    "): " + range("q", iq, nq) + ", " + range("dq", iv, nv));
    if (ff) {
      lines.push_back(
          "     q: position, then unit quaternion (x, y, z, w), which must have norm 1");
      lines.push_back(
          "     (not normalised here); dq: linear, then angular velocity of the body in");
      lines.push_back(
          "     its own axes; ddq: their derivative; tau: force, then moment about the");
      lines.push_back("     body's origin, in its axes.");
    } else if (planar) {
      lines.push_back(
          "     q: (x, y, cos t, sin t), (cos t, sin t) of norm 1; dq: (vx, vy, wz) in the");
      lines.push_back("     body's axes; tau: (fx, fy, tz).");
    }
    iq += nq;
    iv += nv;
  }
  if (!code.contacts.empty()) {
    lines.push_back(
        "Contact wrenches f, 6 per link: force, then moment about the link's origin, in");
    lines.push_back(code.contact_world ? "world axes:" : "the link's own axes:");
    for (size_t c = 0; c < code.contacts.size(); ++c)
      lines.push_back("  " + std::to_string(c + 1) + ". " + code.contacts[c] + ": " +
                      range("f", 6 * static_cast<int>(c), 6));
    lines.push_back("inverse_dynamics gives tau = M(q) ddq + b(q, dq) + g(q) - sum_c J_c^T f_c.");
  }
  return lines;
}

}  // namespace

std::vector<std::string> describe(const GeneratedCode& code) {
  std::vector<std::string> lines;
  const ParameterSet& ps = code.params;
  lines.push_back("Generated by mindyn from robot '" + code.robot + "' (" + std::to_string(code.n) +
                  " joints).");
  std::string what = ps.base ? "Newton-Euler recursion in the " + std::to_string(ps.size()) +
                                   " base parameters (equations-of-motion set)"
                             : "Newton-Euler recursion in the " + std::to_string(ps.size()) +
                                   " classical parameters";
  std::vector<std::string> extras;
  if (ps.layout.rotor) extras.push_back("rotor inertia");
  if (ps.layout.friction) extras.push_back(internal::frictionWords(code.friction.kind));
  if (ps.offsets) extras.push_back("a torque offset per joint (not in the gravity torque)");
  if (!extras.empty()) {
    what += ", with ";
    for (size_t i = 0; i < extras.size(); ++i) what += (i ? " and " : "") + extras[i];
  }
  std::istringstream whatLines(wrap(what + ".", 90, "  "));
  for (std::string part; std::getline(whatLines, part);) lines.push_back(part);
  lines.push_back("Units SI; gravity and all frames as in the robot description.");
  for (const auto& l : internal::driveLines(code)) lines.push_back(l);
  if (code.floating) {
    for (const auto& l : floatingLines(code)) lines.push_back(l);
  } else if (!code.parents.empty()) {
    lines.push_back(
        "A tree: the joints in the order of q, dq, ddq and tau, each with the one it is");
    lines.push_back("mounted on:");
    for (size_t k = 0; k < code.joints.size(); ++k) {
      const int p = code.parents[k];
      lines.push_back("  " + std::to_string(k + 1) + ". " + code.joints[k] + " (on " +
                      (p < 0 ? std::string("the base") : code.joints[static_cast<size_t>(p)]) +
                      ")");
    }
  }
  const GeometrySnap snap = geometrySnap(code);
  if (snap.count > 0) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "Geometry: %d constants within %.2g of 0 or +-1 taken as exact (largest "
                  "change %.2g).",
                  snap.count, kGeometrySnap, snap.largest);
    lines.push_back(buf);
  }
  lines.push_back("");
  lines.push_back(
      "Operation counts (multiplications, additions, sines and cosines), the formulation");
  lines.push_back(std::string("chosen for the fewest ") +
                  (code.objective == Objective::Additions ? "additions" : "operations") + ":");
  for (const auto& f : code.functions) {
    const OpCount& c = f.program.count;
    std::string l = "  " + std::string(toString(f.function)) + ": " + std::to_string(c.mul) +
                    " mul, " + std::to_string(c.add) + " add, " + std::to_string(c.trig) +
                    " sin/cos";
    if (c.neg) l += ", " + std::to_string(c.neg) + " neg";
    if (c.sign) l += ", " + std::to_string(c.sign) + " sign";
    if (c.tanh) l += ", " + std::to_string(c.tanh) + " tanh";
    if (c.exp) l += ", " + std::to_string(c.exp) + " exp";
    lines.push_back(l);
  }
  lines.push_back("");
  if (code.numeric) {
    lines.push_back("Parameter values baked in (inverse_dynamics and gravity take no p);");
    lines.push_back("the regressor's columns, in order:");
  } else {
    lines.push_back("Parameters p, in order, with the values of the robot description or of");
    lines.push_back("the given file:");
  }
  for (int b = 0; b < ps.size(); ++b) {
    std::string l = std::to_string(b + 1) + ". " +
                    (ps.formulas.empty() ? ps.names[b] : ps.formulas[b]) + "  [" +
                    literal(code.values[b]) + "]";
    std::istringstream split(wrap(l, 90, "      "));
    std::string part;
    while (std::getline(split, part)) lines.push_back("  " + part);
  }
  return lines;
}

namespace {

// The sine-cosine routine of the generated source: mindyn::sinCos (mindyn/sincos.hpp, where the
// method is described) written out in C with the same constants.
std::string sincosRoutine(const std::string& name) {
  using namespace sincos_constants;
  // a + z b, as "a + z * b" or "a - z * |b|"
  const auto pair = [](double a, double b) {
    return literal(a) + (b < 0 ? " - z * " : " + z * ") + literal(std::abs(b));
  };
  std::ostringstream os;
  os << "/* *s = sin(x), *c = cos(x): for |x| <= 1e6 without a branch or a call (x = k pi/2 + r,\n"
        " * |r| <= pi/4, polynomials in r, the quadrant from a table), within 2.2e-16 of the C\n"
        " * library; beyond, and for NaN and infinities, the C library's. Reassociating compiler\n"
        " * options (-ffast-math) merge the two parts of pi/2: the error is then about 1e-16 |x|. "
        "*/\n";
  os << "static const double " << name << "_quadrant[4][2] = {";
  for (int k = 0; k < 4; ++k)
    os << (k ? ", {" : "{") << literal(kQuadrant[k][0]) << ", " << literal(kQuadrant[k][1]) << "}";
  os << "};\n\n";
  os << "static inline void " << name << "_sincos(const double x, double* s, double* c) {\n";
  os << "  if (!(fabs(x) <= " << literal(kLimit) << ")) {\n"
     << "    *s = sin(x);\n    *c = cos(x);\n    return;\n  }\n";
  os << "  const long k = (long)(x * " << literal(kTwoOverPi) << " + "
     << literal(static_cast<double>(kOffset) + 0.5) << ") - " << kOffset << "L;\n";
  os << "  const double kd = (double)k;\n";
  os << "  const double r = (x - kd * " << literal(kHalfPiHead) << ") - kd * "
     << literal(kHalfPiTail) << ";\n";
  os << "  const double z = r * r;\n  const double z2 = z * z;\n  const double z4 = z2 * z2;\n";
  for (const auto& [v, coef] : {std::pair{'s', kSin}, std::pair{'c', kCos}})
    for (int i = 0; i < 6; i += 2)
      os << "  const double " << v << i << i + 1 << " = " << pair(coef[i], coef[i + 1]) << ";\n";
  os << "  const double sr = r + r * z * (s01 + z2 * s23 + z4 * s45);\n";
  os << "  const double cr = (1.0 - 0.5 * z) + z2 * (c01 + z2 * c23 + z4 * c45);\n";
  os << "  const double* const t = " << name << "_quadrant[(unsigned long)k & 3u];\n";
  os << "  *s = sr * t[0] + cr * t[1];\n  *c = cr * t[0] - sr * t[1];\n}\n";
  return os.str();
}

class CWriter {
 public:
  CWriter(const GeneratedFunction& f, const std::string& prefix, CTrig trig)
      : f_(f), prefix_(prefix), trig_(trig), name_(f.graph.size()) {}

  std::string operand(Ref r) const {
    const Node& n = f_.graph.node(r.id());
    switch (n.op) {
      case Op::Const:
        return literal(n.value);
      case Op::Input:
        return std::string(inputName(n.kind)) + "[" + std::to_string(n.index) + "]";
      default:
        return name_[r.id()];
    }
  }
  std::string signedValue(Ref r) const {
    if (f_.graph.isConstant(r)) return literal(f_.graph.constantValue(r));
    return (r.negative() ? "-" : "") + operand(r);
  }

  void body(std::ostream& os, const std::string& out) {
    // The sines and cosines (and their arguments, q + offset) first: they depend on q alone,
    // and started together they overlap with each other and with the recursion that waits on
    // them (about 10 % less time per call than computing each where it is first used).
    const Graph& g = f_.graph;
    std::vector<char> early(g.size(), 0);
    std::vector<int> stack;
    for (int id : f_.program.order)
      if (g.node(id).op == Op::Sin || g.node(id).op == Op::Cos) stack.push_back(id);
    while (!stack.empty()) {
      const int id = stack.back();
      stack.pop_back();
      const Node& n = g.node(id);
      if (early[id] || n.op == Op::Const || n.op == Op::Input) continue;
      early[id] = 1;
      stack.push_back(n.a.id());
      if (n.op == Op::Add || n.op == Op::Mul) stack.push_back(n.b.id());
    }
    std::vector<int> order;
    for (int pass = 1; pass >= 0; --pass)
      for (int id : f_.program.order)
        if (early[id] == pass) order.push_back(id);
    // Inline trig: one routine call per argument gives its sine and cosine together.
    std::unordered_map<std::uint32_t, std::pair<int, int>> trigOf;  // argument -> (sin, cos)
    for (int id : order) {
      const Node& n = g.node(id);
      if (n.op != Op::Sin && n.op != Op::Cos) continue;
      auto& sc = trigOf.try_emplace(n.a.bits(), -1, -1).first->second;
      (n.op == Op::Sin ? sc.first : sc.second) = id;
    }
    int t = 0;
    for (int id : order) {
      const Node& n = f_.graph.node(id);
      if (trig_ == CTrig::Inline && (n.op == Op::Sin || n.op == Op::Cos)) {
        if (!name_[id].empty()) continue;  // named with its partner
        const auto [s, c] = trigOf.at(n.a.bits());
        const std::string sn = "t" + std::to_string(t++), cn = "t" + std::to_string(t++);
        if (s >= 0) name_[s] = sn;
        if (c >= 0) name_[c] = cn;
        os << "  double " << sn << ", " << cn << ";\n";
        os << "  " << prefix_ << "_sincos(" << operand(n.a) << ", &" << sn << ", &" << cn << ");\n";
        continue;
      }
      name_[id] = "t" + std::to_string(t++);
      os << "  const double " << name_[id] << " = ";
      switch (n.op) {
        case Op::Sin:
          os << "sin(" << operand(n.a) << ")";
          break;
        case Op::Cos:
          os << "cos(" << operand(n.a) << ")";
          break;
        case Op::Sign:
          os << "(double)((" << operand(n.a) << " > 0.0) - (" << operand(n.a) << " < 0.0))";
          break;
        case Op::Tanh:
          os << "tanh(" << operand(n.a) << ")";
          break;
        case Op::Exp:
          os << "exp(" << signedValue(n.a) << ")";
          break;
        case Op::Add:
          os << operand(n.a) << (n.b.negative() ? " - " : " + ") << operand(n.b);
          break;
        case Op::Mul:
          os << operand(n.a) << " * " << operand(n.b);
          break;
        default:
          break;
      }
      os << ";\n";
    }
    for (size_t i = 0; i < f_.outputs.size(); ++i)
      os << "  " << out << "[" << i << "] = " << signedValue(f_.outputs[i]) << ";\n";
  }

  bool usesTrig() const {
    for (int id : f_.program.order)
      if (f_.graph.node(id).op == Op::Sin || f_.graph.node(id).op == Op::Cos) return true;
    return false;
  }

  bool uses(InputKind k) const {
    for (int id = 0; id < f_.graph.size(); ++id) {
      const Node& n = f_.graph.node(id);
      if (n.op == Op::Input && n.kind == k && f_.program.uses[id] > 0) return true;
    }
    return false;
  }

 private:
  const GeneratedFunction& f_;
  std::string prefix_;
  CTrig trig_;
  std::vector<std::string> name_;
};

std::string signature(const GeneratedCode& code, const GeneratedFunction& f) {
  // q of nq entries, dq, ddq and tau of nv: both n but for a floating base
  const int nq = code.floating ? code.nq : code.n, nv = code.floating ? code.nv : code.n;
  const std::string Q = std::to_string(nq), N = std::to_string(nv),
                    NP = std::to_string(code.params.size());
  std::string s = "void " + code.name + "_" + toString(f.function) + "(const double q[" + Q + "]";
  if (f.function != Function::Gravity)
    s += ", const double dq[" + N + "], const double ddq[" + N + "]";
  if (f.function == Function::Regressor)
    return s + ", double W[" + std::to_string(nv * code.params.size()) + "])";
  if (!f.numeric) s += ", const double p[" + NP + "]";
  if (f.contacts) s += ", const double f[" + std::to_string(6 * f.contacts) + "]";
  return s + ", double tau[" + N + "])";
}

std::string upper(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::toupper(c); });
  return s;
}

}  // namespace

void internal::writeCBody(std::ostream& os, const GeneratedFunction& f, const std::string& prefix,
                          CTrig trig, const std::string& out) {
  CWriter(f, prefix, trig).body(os, out);
}

bool internal::usesTrig(const GeneratedFunction& f) {
  return CWriter(f, "", CTrig::Libm).usesTrig();
}

std::string internal::sincosSource(const std::string& prefix) { return sincosRoutine(prefix); }

CFiles emitC(const GeneratedCode& code, const std::string& header_name, CTrig trig) {
  checkIdentifier(code.name);
  const std::string NAME = upper(code.name);
  const int np = code.params.size();
  std::ostringstream h, c;
  h << "/*\n";
  for (const auto& l : describe(code)) h << (l.empty() ? " *" : " * " + l) << "\n";
  h << " *\n * The regressor W is row-major, " << (code.floating ? "NV" : "N")
    << " x NP: tau[i] = sum_j W[i * NP + j] p[j]";
  h << (code.params.layout.friction ? " (friction\n * columns as above)" : "") << ".\n */\n";
  h << "#ifndef " << NAME << "_H\n#define " << NAME << "_H\n\n";
  h << "#ifdef __cplusplus\nextern \"C\" {\n#endif\n\n";
  if (code.floating) {
    h << "#define " << NAME << "_NQ " << code.nq << "\n";
    h << "#define " << NAME << "_NV " << code.nv << "\n";
    h << "#define " << NAME << "_NC " << code.contacts.size() << "\n";
  } else {
    h << "#define " << NAME << "_N " << code.n << "\n";
  }
  h << "#define " << NAME << "_NP " << np << "\n\n";
  h << "/* Parameter names and values, in the order of p. */\n";
  h << "extern const char* const " << code.name << "_parameter_names[" << np << "];\n";
  h << "extern const double " << code.name << "_parameter_values[" << np << "];\n\n";
  for (const auto& f : code.functions) h << signature(code, f) << ";\n";
  h << "\n#ifdef __cplusplus\n}\n#endif\n\n#endif\n";

  c << "/* " << header_name << ": see the header for the parameters and operation counts. */\n";
  c << "#include \"" << header_name << "\"\n\n#include <math.h>\n\n";
  c << "const char* const " << code.name << "_parameter_names[" << np << "] = {";
  for (int b = 0; b < np; ++b)
    c << (b % 8 ? " " : "\n    ") << "\"" << code.params.names[b] << "\",";
  c << "\n};\n\n";
  c << "const double " << code.name << "_parameter_values[" << np << "] = {";
  for (int b = 0; b < np; ++b) c << "\n    " << literal(code.values[b]) << ",";
  c << "\n};\n";
  bool trigUsed = false;
  for (const auto& f : code.functions) trigUsed |= CWriter(f, code.name, trig).usesTrig();
  if (trig == CTrig::Inline && trigUsed) c << "\n" << sincosRoutine(code.name);
  for (const auto& f : code.functions) {
    CWriter w(f, code.name, trig);
    c << "\n" << signature(code, f) << " {\n";
    for (InputKind k : {InputKind::Q, InputKind::DQ, InputKind::DDQ, InputKind::P}) {
      const bool present =
          k == InputKind::Q ||
          ((k == InputKind::DQ || k == InputKind::DDQ) && f.function != Function::Gravity) ||
          (k == InputKind::P && f.function != Function::Regressor && !f.numeric);
      if (present && !w.uses(k)) c << "  (void)" << inputName(k) << ";\n";
    }
    w.body(c, f.function == Function::Regressor ? "W" : "tau");
    c << "}\n";
  }
  return {h.str(), c.str()};
}

}  // namespace mindyn::codegen
