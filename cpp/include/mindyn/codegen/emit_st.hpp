// IEC 61131-3 Structured Text emitter (CODESYS, TwinCAT): one FUNCTION_BLOCK per function,
//
//   FUNCTION_BLOCK NAME_inverse_dynamics
//     VAR_INPUT q, dq, ddq : ARRAY[1..N] OF LREAL; p : ARRAY[1..NP] OF LREAL; END_VAR
//     VAR_OUTPUT tau : ARRAY[1..N] OF LREAL; END_VAR
//
// (NAME_gravity without dq, ddq; NAME_regressor with W : ARRAY[1..N, 1..NP] OF LREAL and no p;
// with baked-in parameters no p). Temporaries are local LREAL variables, reused once dead; only
// SIN and COS are called, products are written out (no **), one operation per line.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <string>

#include "mindyn/codegen/newton_euler.hpp"

namespace mindyn::codegen {

std::string emitST(const GeneratedCode& code);

}  // namespace mindyn::codegen
