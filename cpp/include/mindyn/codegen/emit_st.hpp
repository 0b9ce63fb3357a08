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
// A program is first built as blocks (STProgram: its comments, and per FUNCTION_BLOCK the typed
// variables of each section, a note and the statements), from which writeST writes the text and
// other writers (the PLCopen XML of the Python package) write other forms of the same program.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "mindyn/codegen/newton_euler.hpp"

namespace mindyn::codegen {

/// One variable of a function block: `name : type;` or `name : ARRAY[1..N, ...] OF type;`.
struct STVariable {
  std::string name;
  std::string type;                       ///< IEC 61131-3 elementary type: "LREAL" or "BOOL"
  std::vector<std::pair<int, int>> dims;  ///< array bounds (lower, upper); empty for a scalar
};

/// The declaration's type: "LREAL", "ARRAY[1..6] OF LREAL", "ARRAY[1..6, 1..36] OF LREAL".
std::string declaredType(const STVariable& v);

/// One FUNCTION_BLOCK.
struct STFunctionBlock {
  std::string name;
  std::vector<STVariable> inputs;   ///< VAR_INPUT
  std::vector<STVariable> outputs;  ///< VAR_OUTPUT
  std::vector<STVariable> locals;   ///< VAR (settings, state and temporaries)
  std::string note;                 ///< a comment after the declarations, or empty
  std::string body;                 ///< the statements, each line ending in a line break
};

/// A generated Structured Text program: comment lines before the blocks, then the blocks.
struct STProgram {
  std::vector<std::string> comments;  ///< each written as one (* ... *), may span lines
  std::vector<STFunctionBlock> blocks;
};

/// The text: each comment as (* c *) ((* *) when empty), then per block a blank line,
/// FUNCTION_BLOCK NAME, the sections with one declaration per line (VAR only when it has
/// variables), the note as (* note *), the body and END_FUNCTION_BLOCK.
std::string writeST(const STProgram& program);

/// The program of the inverse dynamics, gravity and regressor function blocks.
STProgram programST(const GeneratedCode& code);
/// writeST(programST(code)).
std::string emitST(const GeneratedCode& code);

}  // namespace mindyn::codegen
