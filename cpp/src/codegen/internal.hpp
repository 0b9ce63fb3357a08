// Declarations shared by the code generator's sources and its tests, not installed: one fixed
// formulation of a generated function (the search in generate / generateSlotineLi keeps the
// cheapest), and the function bodies the emitters write, for code written around them (the
// controller steps).
#pragma once

#include <ostream>
#include <string>

#include "mindyn/codegen/emit_c.hpp"
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

}  // namespace mindyn::codegen::internal
