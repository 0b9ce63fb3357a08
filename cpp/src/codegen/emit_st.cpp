#include "mindyn/codegen/emit_st.hpp"

#include <sstream>
#include <utility>

#include "internal.hpp"
#include "mindyn/codegen/emit_c.hpp"

namespace mindyn::codegen {

namespace {

// t := tanh(a) without TANH (not an IEC 61131-3 function), within 2 ulp, never overflowing:
// +-1 beyond |a| > 20 (tanh rounds to +-1 there), (1 - e) / (1 + e) with e = EXP(-2 |a|) down to
// |a| = 0.125, below that its Taylor series to a^15 (truncation under 3e-18 relative). `t` is
// not `a`.
void writeTanh(std::ostream& os, const std::string& t, const std::string& a) {
  // the series a (1 - x (1/3 - x (2/15 - x (17/315 - ...)))), x = a^2
  static const double c[] = {
      1.0 / 3.0,         2.0 / 15.0,          17.0 / 315.0,          62.0 / 2835.0,
      1382.0 / 155925.0, 21844.0 / 6081075.0, 929569.0 / 638512875.0};
  os << "IF " << a << " > 20.0 THEN\n  " << t << " := 1.0;\n";
  os << "ELSIF " << a << " < -20.0 THEN\n  " << t << " := -1.0;\n";
  os << "ELSIF " << a << " > 0.125 THEN\n  " << t << " := EXP(-2.0 * " << a << ");\n  " << t
     << " := (1.0 - " << t << ") / (1.0 + " << t << ");\n";
  os << "ELSIF " << a << " < -0.125 THEN\n  " << t << " := EXP(2.0 * " << a << ");\n  " << t
     << " := (" << t << " - 1.0) / (1.0 + " << t << ");\n";
  os << "ELSE\n  " << t << " := " << a << " * " << a << ";\n  " << t << " := " << a << " * (1.0";
  const int m = static_cast<int>(sizeof c / sizeof c[0]);
  for (int k = 0; k < m; ++k) {
    os << (k % 2 ? "\n    - " : " - ") << t << " * " << (k + 1 < m ? "(" : "")
       << literal(c[k], true);
  }
  os << std::string(m, ')') << ";\nEND_IF;\n";
}

class STWriter {
 public:
  explicit STWriter(const GeneratedFunction& f, std::string out = "")
      : f_(f), slot_(f.graph.size(), -1), out_(std::move(out)) {}

  std::string operand(Ref r) const {
    const Node& n = f_.graph.node(r.id());
    switch (n.op) {
      case Op::Const:
        return literal(n.value, true);
      case Op::Input:
        return std::string(inputName(n.kind)) + "[" + std::to_string(n.index + 1) + "]";
      default:
        return "t" + std::to_string(slot_[r.id()] + 1);
    }
  }
  std::string signedValue(Ref r) const {
    if (f_.graph.isConstant(r)) return literal(f_.graph.constantValue(r), true);
    return (r.negative() ? "-" : "") + operand(r);
  }
  std::string output(size_t i) const {
    if (!out_.empty()) return out_ + "[" + std::to_string(i + 1) + "]";
    if (f_.function != Function::Regressor) return "tau[" + std::to_string(i + 1) + "]";
    const size_t np = static_cast<size_t>(f_.np);
    return "W[" + std::to_string(i / np + 1) + ", " + std::to_string(i % np + 1) + "]";
  }

  // Statements, with temporaries reused once their last reader has run.
  void body(std::ostream& os) {
    const auto& order = f_.program.order;
    std::vector<int> last(f_.graph.size(), -1);
    for (size_t i = 0; i < order.size(); ++i) {
      const Node& n = f_.graph.node(order[i]);
      last[n.a.id()] = static_cast<int>(i);
      if (n.op == Op::Add || n.op == Op::Mul) last[n.b.id()] = static_cast<int>(i);
    }
    std::vector<std::vector<size_t>> outputsOf(f_.graph.size());
    for (size_t i = 0; i < f_.outputs.size(); ++i) outputsOf[f_.outputs[i].id()].push_back(i);
    std::vector<int> free;
    for (size_t i = 0; i < order.size(); ++i) {
      const int id = order[i];
      const Node& n = f_.graph.node(id);
      const std::string a = operand(n.a);
      const std::string b = (n.op == Op::Add || n.op == Op::Mul) ? operand(n.b) : "";
      // operands whose last reader is this statement free their slots for the result, except
      // for tanh, which writes its result before it last reads its operand
      auto release = [&] {
        for (Ref r : {n.a, n.b})
          if (slot_[r.id()] >= 0 && last[r.id()] == static_cast<int>(i)) {
            free.push_back(slot_[r.id()]);
            last[r.id()] = -2;
          }
      };
      if (n.op != Op::Tanh) release();
      if (free.empty()) {
        slot_[id] = slots_++;
      } else {
        slot_[id] = free.back();
        free.pop_back();
      }
      if (n.op == Op::Tanh) release();
      const std::string t = operand(Ref(id, false));
      switch (n.op) {
        case Op::Sin:
          os << t << " := SIN(" << a << ");\n";
          break;
        case Op::Cos:
          os << t << " := COS(" << a << ");\n";
          break;
        case Op::Sign:
          os << "IF " << a << " > 0.0 THEN\n  " << t << " := 1.0;\nELSIF " << a << " < 0.0 THEN\n  "
             << t << " := -1.0;\nELSE\n  " << t << " := 0.0;\nEND_IF;\n";
          break;
        case Op::Tanh:
          writeTanh(os, t, a);
          break;
        case Op::Exp:
          os << t << " := EXP(" << signedValue(n.a) << ");\n";
          break;
        case Op::Add:
          os << t << " := " << a << (n.b.negative() ? " - " : " + ") << b << ";\n";
          break;
        case Op::Mul:
          os << t << " := " << a << " * " << b << ";\n";
          break;
        default:
          break;
      }
      for (size_t o : outputsOf[id])
        os << output(o) << " := " << signedValue(f_.outputs[o]) << ";\n";
      if (last[id] == -1) {  // read by outputs only
        free.push_back(slot_[id]);
        last[id] = -2;
      }
    }
    for (size_t o = 0; o < f_.outputs.size(); ++o) {
      const Op op = f_.graph.node(f_.outputs[o].id()).op;
      if (op == Op::Const || op == Op::Input)
        os << output(o) << " := " << signedValue(f_.outputs[o]) << ";\n";
    }
  }
  int slots() const { return slots_; }

 private:
  const GeneratedFunction& f_;
  std::vector<int> slot_;
  int slots_ = 0;
  std::string out_;
};

}  // namespace

int internal::writeSTBody(std::ostream& os, const GeneratedFunction& f, const std::string& out) {
  STWriter w(f, out);
  w.body(os);
  return w.slots();
}

std::string declaredType(const STVariable& v) {
  if (v.dims.empty()) return v.type;
  std::string t = "ARRAY[";
  for (size_t i = 0; i < v.dims.size(); ++i)
    t +=
        (i ? ", " : "") + std::to_string(v.dims[i].first) + ".." + std::to_string(v.dims[i].second);
  return t + "] OF " + v.type;
}

std::string writeST(const STProgram& program) {
  std::ostringstream os;
  for (const auto& c : program.comments) os << (c.empty() ? "(* *)" : "(* " + c + " *)") << "\n";
  for (const auto& b : program.blocks) {
    checkIdentifier(b.name);
    os << "\nFUNCTION_BLOCK " << b.name << "\n";
    for (const auto& [section, vars] :
         {std::pair{"VAR_INPUT", &b.inputs}, std::pair{"VAR_OUTPUT", &b.outputs},
          std::pair{"VAR", &b.locals}}) {
      if (vars->empty() && std::string(section) == "VAR") continue;
      os << section << "\n";
      for (const auto& v : *vars) os << "  " << v.name << " : " << declaredType(v) << ";\n";
      os << "END_VAR\n";
    }
    if (!b.note.empty()) os << "(* " << b.note << " *)\n";
    os << b.body << "END_FUNCTION_BLOCK\n";
  }
  return os.str();
}

STProgram programST(const GeneratedCode& code) {
  checkIdentifier(code.name);
  if (code.floating)
    throw ModelError("Structured Text is generated for a fixed base only; robot '" + code.robot +
                     "' has a floating base (generate C)");
  const int n = code.n, np = static_cast<int>(code.params.size());
  const auto vec = internal::stVector;
  STProgram p;
  p.comments = describe(code);
  p.comments.push_back("Arrays are 1-based: q[k] is joint k, p[j] parameter j; regressor W[i, j].");
  for (const auto& f : code.functions) {
    STFunctionBlock b;
    b.name = code.name + "_" + toString(f.function);
    b.inputs.push_back(vec("q", n));
    if (f.function != Function::Gravity) {
      b.inputs.push_back(vec("dq", n));
      b.inputs.push_back(vec("ddq", n));
    }
    if (f.function != Function::Regressor && !f.numeric) b.inputs.push_back(vec("p", np));
    if (f.function == Function::Regressor)
      b.outputs.push_back(STVariable{"W", "LREAL", {{1, n}, {1, np}}});
    else
      b.outputs.push_back(vec("tau", n));
    STWriter w(f);
    std::ostringstream body;
    w.body(body);
    for (int s = 0; s < w.slots(); ++s)
      b.locals.push_back(internal::stScalar("t" + std::to_string(s + 1)));
    const OpCount& c = f.program.count;
    std::ostringstream note;
    note << c.mul << " mul, " << c.add << " add, " << c.trig << " sin/cos";
    for (const auto& [count, what] :
         {std::pair{c.sign, " sign"}, std::pair{c.tanh, " tanh"}, std::pair{c.exp, " exp"}})
      if (count) note << ", " << count << what;
    b.note = note.str();
    b.body = body.str();
    p.blocks.push_back(std::move(b));
  }
  return p;
}

std::string emitST(const GeneratedCode& code) { return writeST(programST(code)); }

}  // namespace mindyn::codegen
