// The parameter sets a generated function takes (pi = E p): the equations-of-motion base set,
// all classical parameters of a layout, and either with a constant torque offset per joint (the
// layout's joint block, or appended by withOffsets).
#include <string>

#include "mindyn/codegen/newton_euler.hpp"

namespace mindyn::codegen {

void checkCodegenJoints(const Model& model, ParameterLayout layout) {
  for (int k = 0; k < model.nq(); ++k) {
    const Joint& j = model.joints[k];
    if (j.singleDof()) continue;
    const bool root = j.type == JointType::FreeFlyer || j.type == JointType::Planar;
    if (!root)
      throw ModelError(
          "code generation takes revolute and prismatic joints, and a free-flyer or "
          "planar joint on the fixed base; model '" +
          model.name + "' has the " + toString(j.type) + " joint '" + j.name + "'");
    if (model.parent(k) >= 0)
      throw ModelError(
          "code generation takes a free-flyer or planar joint on the fixed base "
          "only; the " +
          std::string(toString(j.type)) + " joint '" + j.name + "' of model '" + model.name +
          "' is mounted on the joint '" + model.joints[model.parent(k)].name + "'");
    if (layout.rotor || layout.friction || layout.offset)
      throw ModelError(
          "code generation for a floating base takes the inertial parameters only "
          "(no rotor inertia, friction or torque offsets); model '" +
          model.name + "' has the " + toString(j.type) + " joint '" + j.name + "'");
  }
}

// The layout's joint block (torque offsets) is the set's last `offsets` entries; E and `layout`
// cover the link blocks.
ParameterSet baseParameterSet(const Model& model, const BaseParameters& bp) {
  checkCodegenJoints(model, bp.layout);
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
  checkCodegenJoints(model, layout);
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
  checkCodegenJoints(model, model.layout(false, false, true));
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
