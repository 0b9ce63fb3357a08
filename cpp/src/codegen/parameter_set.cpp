// The parameter sets a generated function takes (pi = E p): the equations-of-motion base set,
// all classical parameters of a layout, and either with a constant torque offset per joint.
#include <string>

#include "mindyn/codegen/newton_euler.hpp"

namespace mindyn::codegen {

ParameterSet baseParameterSet(const Model& model, const BaseParameters& bp) {
  requireSingleDof(model, "code generation");
  ParameterSet s;
  s.layout = bp.layout;
  s.base = true;
  s.names = bp.eom.names;
  s.formulas = bp.eom.formulas(bp.classical_names);
  const int P = bp.layout.size(model.nq()), nb = bp.eom.size();
  s.E = Eigen::MatrixXd::Zero(P, nb);
  for (int b = 0; b < nb; ++b) s.E(bp.eom.decision.pivots[b], b) = 1.0;
  s.values = bp.eom.decision.Y * model.parameters(bp.layout);
  return s;
}

ParameterSet classicalParameterSet(const Model& model, ParameterLayout layout) {
  requireSingleDof(model, "code generation");
  ParameterSet s;
  s.layout = layout;
  s.base = false;
  s.names = model.parameterNames(layout);
  const int P = layout.size(model.nq());
  s.E = Eigen::MatrixXd::Identity(P, P);
  s.values = model.parameters(layout);
  return s;
}

ParameterSet withOffsets(const Model& model, ParameterSet s) {
  if (s.offsets) throw ModelError("codegen: the parameter set has torque offsets already");
  const int n = model.nq(), np = s.size();
  for (int k = 0; k < n; ++k) {
    const std::string name = "Off" + std::to_string(k + 1);
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
