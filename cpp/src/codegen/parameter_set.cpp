// The parameter sets a generated function takes (pi = E p): the equations-of-motion base set,
// all classical parameters of a layout, and either with a constant torque offset per joint (the
// layout's joint block, or appended by withOffsets).
#include <string>

#include "mindyn/codegen/newton_euler.hpp"

namespace mindyn::codegen {

// The layout's joint block (torque offsets) is the set's last `offsets` entries; E and `layout`
// cover the link blocks.
ParameterSet baseParameterSet(const Model& model, const BaseParameters& bp) {
  requireSingleDof(model, "code generation");
  ParameterSet s;
  s.layout = bp.layout.links();
  s.base = true;
  s.names = bp.eom.names;
  s.formulas = bp.eom.formulas(bp.classical_names);
  const int P = s.layout.size(model.nq()), nb = bp.eom.size();
  s.E = Eigen::MatrixXd::Zero(P, nb);
  for (int b = 0; b < nb; ++b)
    if (bp.eom.decision.pivots[b] < P) s.E(bp.eom.decision.pivots[b], b) = 1.0;
  s.values = bp.eom.decision.Y * model.parameters(bp.layout);
  s.offsets = bp.layout.offset ? model.nq() : 0;
  return s;
}

ParameterSet classicalParameterSet(const Model& model, ParameterLayout layout) {
  requireSingleDof(model, "code generation");
  ParameterSet s;
  s.layout = layout.links();
  s.base = false;
  s.names = model.parameterNames(layout);
  const int P = s.layout.size(model.nq());
  s.E = Eigen::MatrixXd::Identity(P, layout.size(model.nq()));
  s.values = model.parameters(layout);
  s.offsets = layout.offset ? model.nq() : 0;
  return s;
}

ParameterSet withOffsets(const Model& model, ParameterSet s) {
  if (s.offsets) throw ModelError("codegen: the parameter set has torque offsets already");
  const int n = model.nq(), np = s.size();
  for (int k = 0; k < n; ++k) {
    const std::string name = offsetName(k);
    s.names.push_back(name);
    if (s.base) s.formulas.push_back(name + " = " + name);
  }
  s.E.conservativeResize(Eigen::NoChange, np + n);
  s.E.rightCols(n).setZero();
  s.values.conservativeResize(np + n);
  s.values.tail(n).setZero();
  s.offsets = n;
  return s;
}

}  // namespace mindyn::codegen
