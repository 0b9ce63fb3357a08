// C99 emitter: a header and a source file, depending on nothing but math.h, allocating nothing.
//
//   void NAME_inverse_dynamics(const double q[N], const double dq[N], const double ddq[N],
//                              const double p[NP], double tau[N]);
//   void NAME_gravity(const double q[N], const double p[NP], double tau[N]);
//   void NAME_regressor(const double q[N], const double dq[N], const double ddq[N],
//                       double W[N * NP]);          /* row-major: tau = W p */
//
// A floating base (a free-flyer or planar joint on the fixed base, GeneratedCode::floating): q has
// NQ entries, dq, ddq and tau NV (NAME_NQ, NAME_NV in place of NAME_N), and an inverse dynamics
// with contacts takes `const double f[6 * NC]` after p (tau = rnea - sum_c J_c^T f_c).
//
// With baked-in (numeric) parameters the `p` argument is absent. The header lists the
// parameters in order, with their definitions, in a comment and as NAME_parameter_names. Each
// function computes all its sines and cosines first, then the recursion in graph order.
//
// Sines and cosines: by default (CTrig::Inline) each angle's pair comes from a static routine in
// the source, without branches or calls for |x| <= 1e6 (the C library's sin and cos beyond, and
// for NaN and infinities), within 2.2e-16 of the C library; CTrig::Libm calls sin and cos.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <string>

#include "mindyn/codegen/newton_euler.hpp"

namespace mindyn::codegen {

struct CFiles {
  std::string header;
  std::string source;
};

/// How the generated C evaluates sines and cosines.
enum class CTrig {
  Inline,  ///< a branch-free sine-cosine routine in the generated source
  Libm,    ///< sin and cos of math.h
};

/// `header_name` is the file name the source includes (e.g. "puma560_dyn.h").
CFiles emitC(const GeneratedCode& code, const std::string& header_name, CTrig trig = CTrig::Inline);

/// A double as a C / Structured Text literal that reads back to the same value.
std::string literal(double v, bool structured_text = false);

/// Shared by the emitters: the comment lines describing the generated code.
std::vector<std::string> describe(const GeneratedCode& code);

}  // namespace mindyn::codegen
