// IEC 61131-3 Structured Text emitter (CODESYS, TwinCAT): one FUNCTION_BLOCK per function,
//
//   FUNCTION_BLOCK NAME_inverse_dynamics
//     VAR_INPUT q, dq, ddq : ARRAY[1..N] OF LREAL; p : ARRAY[1..NP] OF LREAL; END_VAR
//     VAR_OUTPUT tau : ARRAY[1..N] OF LREAL; END_VAR
//
// (NAME_gravity without dq, ddq; NAME_regressor with W : ARRAY[1..N, 1..NP] OF LREAL and no p;
// with baked-in parameters no p). Temporaries are local LREAL variables, reused once dead; only
// SIN and COS are called, products are written out (no **), one operation per line.
#pragma once

#include <ostream>
#include <string>

#include "mindyn/codegen/newton_euler.hpp"

namespace mindyn::codegen {

std::string emitST(const GeneratedCode& code);

namespace detail {
/// The statements of one function with its outputs assigned to out[1], out[2], ...; returns
/// the number of LREAL temporaries t1 .. tK they use.
int writeSTBody(std::ostream& os, const GeneratedFunction& f, const std::string& out);
}  // namespace detail

}  // namespace mindyn::codegen
