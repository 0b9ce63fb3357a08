// Declarations shared by the code generator's sources and its tests, not installed: one fixed
// formulation of a generated function (the search in generate / generateSlotineLi keeps the
// cheapest), and the function bodies the emitters write, for code written around them (the
// controller steps).
#pragma once

#include <cmath>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include "mindyn/codegen/emit_c.hpp"
#include "mindyn/codegen/emit_st.hpp"
#include "mindyn/codegen/newton_euler.hpp"

namespace mindyn::codegen::internal {

/// The recursion with one fixed choice for every link: `form` 0 forms each wrench in the link
/// frame; 1, 2, 3 in the joint frame before the motion (revolute joints), with the inertia
/// turned entry by entry, keeping its trace, or split; +4: the moment of the first moment taken
/// after the motion.
GeneratedFunction generateWithLinkForm(const Model& model, const ParameterSet& params,
                                       Function function, int form);

/// The Slotine-Li products in one given form.
GeneratedFunction generateSlotineLiForm(const Model& model, const ParameterSet& params,
                                        bool normalised, SlotineLiForm form);

/// The words of a friction model in a header ("viscous and smooth Coulomb friction").
std::string frictionWords(FrictionKind kind);
/// The lines of a header that say where rotor inertia and friction act (the motors' rows of T)
/// and the friction formula with its velocity scales, when the parameters have them.
std::vector<std::string> driveLines(const GeneratedCode& code);

/// C: the opening of a step's header: `lines` as its comment, the include guard FN_H (`fn` in
/// capitals), extern "C" and the sizes FN_N = n and FN_NP = np.
void openStepHeader(std::ostream& h, const std::string& fn, const std::vector<std::string>& lines,
                    int n, int np);

/// C: the statements of one function, its outputs assigned to out[0], out[1], ...
void writeCBody(std::ostream& os, const GeneratedFunction& f, const std::string& prefix, CTrig trig,
                const std::string& out);
/// C: whether the function calls sine or cosine.
bool usesTrig(const GeneratedFunction& f);
/// C: the static sine-cosine routine PREFIX_sincos of CTrig::Inline.
std::string sincosSource(const std::string& prefix);

/// Structured Text: the statements of one function with its outputs assigned to out[1],
/// out[2], ...; returns the number of LREAL temporaries t1 .. tK they use.
int writeSTBody(std::ostream& os, const GeneratedFunction& f, const std::string& out);
/// Structured Text: an LREAL array [1..size], a scalar of `type`.
inline STVariable stVector(const std::string& name, int size) {
  return STVariable{name, "LREAL", {{1, size}}};
}
inline STVariable stScalar(const std::string& name, const std::string& type = "LREAL") {
  return STVariable{name, type, {}};
}

inline void addCount(OpCount& c, long mul, long add) {
  c.mul += mul;
  c.add += add;
}

/// Statements of a step in C or Structured Text (controller and observer steps).
struct Writer {
  bool st;
  std::ostringstream os;
  std::string indent;
  // a setting or state entry: c->name[i] / name[i + 1]
  std::string field(const std::string& name, int i) const {
    return st ? name + "[" + std::to_string(i + 1) + "]"
              : "c->" + name + "[" + std::to_string(i) + "]";
  }
  std::string scalar(const std::string& name) const { return st ? name : "c->" + name; }
  // an argument or local array entry
  std::string at(const std::string& name, int i) const {
    return name + "[" + std::to_string(st ? i + 1 : i) + "]";
  }
  std::string num(double v) const {
    if (std::isinf(v)) v = v > 0 ? 1e300 : -1e300;
    return literal(v, st);
  }
  void set(const std::string& lhs, const std::string& rhs) {
    os << indent << lhs << (st ? " := " : " = ") << rhs << ";\n";
  }
  void clamp(const std::string& x, const std::string& lo, const std::string& hi) {
    if (st) {
      os << indent << "IF " << x << " > " << hi << " THEN\n"
         << indent << "  " << x << " := " << hi << ";\n"
         << indent << "ELSIF " << x << " < " << lo << " THEN\n"
         << indent << "  " << x << " := " << lo << ";\n"
         << indent << "END_IF;\n";
    } else {
      os << indent << "if (" << x << " > " << hi << ") " << x << " = " << hi << ";\n"
         << indent << "else if (" << x << " < " << lo << ") " << x << " = " << lo << ";\n";
    }
  }
  void comment(const std::string& text) {
    os << indent << (st ? "(* " : "/* ") << text << (st ? " *)\n" : " */\n");
  }
};

}  // namespace mindyn::codegen::internal
