// The generated inverse dynamics, gravity torque and regressor (generate, generateCode): the
// symbolic Newton-Euler recursion (builder.hpp) on the stages of every joint (stages.hpp), its
// classical parameters pi = E p of the parameter set (for the regressor, one column of E at a
// time), and the search, joint by joint, for the placement of the along-axis translation and the
// frame of each link's wrench (Plan) with the fewest operations.
#include "mindyn/codegen/newton_euler.hpp"

#include <algorithm>
#include <cctype>
#include <string>
#include <utility>
#include <vector>

#include "builder.hpp"
#include "internal.hpp"

namespace mindyn::codegen {

using internal::AxisShift;
using internal::Builder;
using internal::jointStages;
using internal::LinkForm;
using internal::Plan;

const char* toString(Function f) {
  switch (f) {
    case Function::InverseDynamics:
      return "inverse_dynamics";
    case Function::Gravity:
      return "gravity";
    case Function::Regressor:
      return "regressor";
    case Function::SlotineLi:
      return "slotine_li";
  }
  return "?";
}

namespace {

GeneratedFunction generateWith(const Model& model, const ParameterSet& params, Function function,
                               bool numeric, const Eigen::VectorXd& values, const Plan& plan,
                               const Contacts& contacts) {
  const int n = model.nq(), nv = model.velocitySize(), np = params.size();
  const int P = params.layout.size(n);
  if (params.E.rows() != P || params.E.cols() != np)
    throw ModelError("codegen: the parameter map does not fit the model (" +
                     std::to_string(params.E.rows()) + " x " + std::to_string(params.E.cols()) +
                     ", expected " + std::to_string(P) + " x " + std::to_string(np) + ")");
  const Eigen::VectorXd vals = values.size() ? values : params.values;
  if (vals.size() != np)
    throw ModelError("codegen: " + std::to_string(vals.size()) + " parameter values for " +
                     std::to_string(np) + " parameters");
  if (numeric && !vals.allFinite()) throw ModelError("codegen: parameter values are not finite");
  if (params.offsets != 0 && params.offsets != n)
    throw ModelError("codegen: " + std::to_string(params.offsets) + " torque offsets for " +
                     std::to_string(n) + " joints");
  const int off0 = np - params.offsets;  // the first offset in p
  internal::checkDriveTerms(model, params.layout);

  GeneratedFunction out;
  out.function = function;
  out.n = nv;
  out.np = np;
  out.numeric = numeric && function != Function::Regressor;
  Graph& g = out.graph;
  Builder b(g, model, jointStages(model, plan.shift));
  if (function == Function::InverseDynamics && !contacts.links.empty()) {
    b.setContacts(contacts.links, contacts.world);
    out.contacts = static_cast<int>(contacts.links.size());
  }

  std::vector<Ref> dq(nv, Graph::zero()), ddq(nv, Graph::zero());
  if (function != Function::Gravity)
    for (int k = 0; k < nv; ++k) {
      dq[k] = g.input(InputKind::DQ, k);
      ddq[k] = g.input(InputKind::DDQ, k);
    }
  b.forward(dq, ddq, true);

  auto classical = [&](auto&& entry) {
    std::vector<Ref> pi(P, Graph::zero());
    for (int c = 0; c < P; ++c) pi[c] = entry(c);
    return pi;
  };
  if (function == Function::Regressor) {
    out.outputs.assign(static_cast<size_t>(nv) * np, Graph::zero());
    for (int col = 0; col < off0; ++col) {
      const auto pi = classical([&](int c) { return g.constant(params.E(c, col)); });
      const auto tau = b.torques(pi, params.layout, true, plan.link);
      for (int i = 0; i < nv; ++i) out.outputs[static_cast<size_t>(i) * np + col] = tau[i];
    }
    for (int k = 0; k < params.offsets; ++k)
      out.outputs[static_cast<size_t>(k) * np + off0 + k] = g.constant(1.0);
  } else {
    std::vector<Ref> p(np);
    for (int j = 0; j < np; ++j)
      p[j] = out.numeric ? g.constant(vals[j]) : g.input(InputKind::P, j);
    const auto pi = classical([&](int c) {
      Ref s = Graph::zero();
      for (int j = 0; j < np; ++j)
        if (params.E(c, j) != 0.0) s = g.add(s, g.mul(g.constant(params.E(c, j)), p[j]));
      return s;
    });
    out.outputs = b.torques(pi, params.layout, function == Function::InverseDynamics, plan.link);
    if (function == Function::InverseDynamics)
      for (int k = 0; k < params.offsets; ++k) out.outputs[k] = g.add(out.outputs[k], p[off0 + k]);
  }
  out.program = schedule(g, out.outputs);
  return out;
}

}  // namespace

GeneratedFunction generate(const Model& model, const ParameterSet& params, Function function,
                           bool numeric, const Eigen::VectorXd& values, Objective objective,
                           const Contacts& contacts) {
  checkCodegenJoints(model, params.layout);
  // Choose, joint by joint, where the along-axis translation goes and in which frame the link's
  // wrench is formed, keeping a change when it lowers the operation count; repeat while a
  // pass improves.
  const int n = model.nq();
  Plan plan{std::vector<AxisShift>(n, AxisShift::Keep), std::vector<LinkForm>(n)};
  GeneratedFunction best = generateWith(model, params, function, numeric, values, plan, contacts);
  auto better = [objective](const OpCount& a, const OpCount& b) {
    if (objective == Objective::Additions)
      return a.add < b.add || (a.add == b.add && a.mul < b.mul);
    const long ta = a.mul + a.add, tb = b.mul + b.add;
    return ta < tb || (ta == tb && a.add < b.add);
  };
  auto attempt = [&](const Plan& trial) {
    GeneratedFunction f = generateWith(model, params, function, numeric, values, trial, contacts);
    if (!better(f.program.count, best.program.count)) return false;
    best = std::move(f);
    plan = trial;
    return true;
  };
  std::vector<LinkForm> forms{{0, false}};
  for (int frame = 1; frame <= 3; ++frame)
    for (bool after : {false, true}) forms.push_back({frame, after});
  for (int pass = 0; pass < 3; ++pass) {
    bool improved = false;
    for (int k = n - 1; k >= 0; --k) {
      if (!model.joints[k].singleDof()) continue;  // a floating base's joint: no axis
      for (AxisShift sh : {AxisShift::Keep, AxisShift::ToPre, AxisShift::ToPost}) {
        if (sh == plan.shift[k]) continue;
        Plan trial = plan;
        trial.shift[k] = sh;
        improved |= attempt(trial);
      }
      if (model.joints[k].type == JointType::Revolute)
        for (const LinkForm& form : forms) {
          if (form == plan.link[k]) continue;
          Plan trial = plan;
          trial.link[k] = form;
          improved |= attempt(trial);
        }
    }
    if (!improved) break;
  }
  jointStages(model, plan.shift, &best.snap);
  internal::cleanGeometry<3, 1>(model.gravity, false, &best.snap);
  return best;
}

const char* toString(Objective o) { return o == Objective::Additions ? "additions" : "operations"; }

GeneratedFunction internal::generateWithLinkForm(const Model& model, const ParameterSet& params,
                                                 Function function, int form) {
  const int n = model.nq();
  Plan plan{std::vector<AxisShift>(n, AxisShift::Keep),
            std::vector<LinkForm>(n, LinkForm{form % 4, form >= 4})};
  return generateWith(model, params, function, false, {}, plan, {});
}

void describeModel(GeneratedCode& code, const Model& model) {
  code.robot = model.name;
  code.n = model.nq();
  code.joints.clear();
  code.parents.clear();
  code.motor_side = model.motorSide();
  code.motors = model.transmission.motors;
  code.T = model.transmission.T;
  code.friction = model.friction_model;
  code.floating = !model.singleDof();
  code.nq = model.configSize();
  code.nv = model.velocitySize();
  code.kinds.clear();
  if (model.isSerial() && !code.floating) return;
  for (const Joint& j : model.joints) {
    code.joints.push_back(j.name);
    code.kinds.push_back(j.type);
  }
  for (int k = 0; k < model.nq(); ++k) code.parents.push_back(model.parent(k));
}

GeometrySnap geometrySnap(const GeneratedCode& code) {
  GeometrySnap out;
  for (const auto& f : code.functions) out.include(f.snap);
  return out;
}

void checkIdentifier(const std::string& name) {
  bool ok = !name.empty() && name.size() <= 40 && std::isalpha(static_cast<unsigned char>(name[0]));
  for (char ch : name)
    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '_') ok = false;
  // Structured Text forbids double and trailing underscores.
  if (name.find("__") != std::string::npos || (!name.empty() && name.back() == '_')) ok = false;
  if (!ok)
    throw ModelError("codegen: name '" + name +
                     "' is not an identifier (letters, digits and single underscores, starting "
                     "with a letter, at most 40 characters)");
}

GeneratedCode generateCode(const Model& model, const ParameterSet& params,
                           const std::vector<Function>& functions, const std::string& name,
                           bool numeric, const Eigen::VectorXd& values, Objective objective,
                           const Contacts& contacts) {
  checkIdentifier(name);
  if (functions.empty()) throw ModelError("codegen: no function to generate");
  checkCodegenJoints(model, params.layout);
  GeneratedCode code;
  describeModel(code, model);
  if (!contacts.links.empty() && !code.floating)
    throw ModelError(
        "codegen: contact wrenches apply to a floating base (a free-flyer or planar "
        "root joint); model '" +
        model.name + "' has a fixed base");
  if (!contacts.links.empty() &&
      std::find(functions.begin(), functions.end(), Function::InverseDynamics) == functions.end())
    throw ModelError("codegen: contact wrenches enter the inverse dynamics only; generate it too");
  for (size_t c = 0; c < contacts.links.size(); ++c) {
    const int k = contacts.links[c];
    if (k < 0 || k >= model.nq())
      throw ModelError("codegen: contact link " + std::to_string(k) + " is not a moving link (0.." +
                       std::to_string(model.nq() - 1) + ")");
    for (size_t d = 0; d < c; ++d)
      if (contacts.links[d] == k)
        throw ModelError("codegen: contact link '" + model.link_names[k + 1] + "' given twice");
    code.contacts.push_back(model.link_names[k + 1]);
  }
  code.contact_world = contacts.world;
  code.name = name;
  code.params = params;
  code.values = values.size() ? values : params.values;
  code.numeric = numeric;
  code.objective = objective;
  for (Function f : functions)
    code.functions.push_back(generate(model, params, f, numeric, values, objective, contacts));
  return code;
}

}  // namespace mindyn::codegen
