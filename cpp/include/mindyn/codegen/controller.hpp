// Generated joint-space controllers: one step per controller period, around a generated
// dynamics function, in C99 (a state struct, an init and an allocation-free step function,
// math.h only) and IEC 61131-3 Structured Text (one FUNCTION_BLOCK holding the estimate).
//
//   adaptive-pd (Slotine-Li, the sign convention of mindyn.control.AdaptivePD):
//     e = q - q_d, de = dq - dq_d, dqr = dq_d - Lambda e, ddqr = ddq_d - Lambda de,
//     s = de + Lambda e, tau = sat(Y(q, dq, dqr, ddqr) p - K_D s),
//     p <- clamp(p - T Gamma Y^T s / (1 + nu |Y|^2), p_min, p_max)
//   computed-torque: tau = sat(W(q, dq, ddq_d - K_D de - K_P e) p)
//   gravity-compensation: tau = sat(g(q) p - K_P e - K_D de)
//
// (|Y|^2 only when generated with nu > 0.) Infinite bounds are written as +-1e300.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "mindyn/codegen/emit_c.hpp"
#include "mindyn/codegen/emit_st.hpp"
#include "mindyn/codegen/newton_euler.hpp"

namespace mindyn::codegen {

enum class Controller { AdaptivePD, ComputedTorque, GravityCompensation };

/// "adaptive_pd", "computed_torque", "gravity_compensation".
const char* toString(Controller c);

/// The settings a generated controller starts with (vectors: n or np entries; unused ones may be
/// empty: kp for adaptive-pd, lambda, gamma, nu, p_min, p_max for the others).
struct ControllerSettings {
  Eigen::VectorXd kd, kp, lambda, gamma, p0, p_min, p_max, tau_max;
  double nu = 0.0;
  double period = 0.004;
};

struct ControllerCode {
  Controller kind = Controller::AdaptivePD;
  GeneratedCode code;  // one function: slotine_li, inverse_dynamics or gravity
  ControllerSettings settings;
  OpCount core;  // the generated dynamics function
  OpCount step;  // the whole step (core, the terms around it; divisions not included)
  long divisions = 0;
  std::vector<SlotineLiVariant> variants;       // adaptive-pd: the counts of each product form
  SlotineLiForm form = SlotineLiForm::Columns;  // adaptive-pd: the form chosen
};

/// Checks the settings (sizes, finite gains >= 0, period > 0, p_min <= p0 <= p_max, tau_max > 0;
/// ModelError naming the setting otherwise) and generates the controller.
ControllerCode generateController(const Model& model, const ParameterSet& params, Controller kind,
                                  const ControllerSettings& settings, const std::string& name);

/// C99 header and source: NAME_KIND_t (settings and estimate), NAME_KIND_init, NAME_KIND_step.
CFiles emitControllerC(const ControllerCode& c, const std::string& header_name,
                       CTrig trig = CTrig::Inline);

/// Structured Text: FUNCTION_BLOCK NAME_KIND.
/// Its blocks (see STProgram), and their text writeST(controllerProgramST(c)).
STProgram controllerProgramST(const ControllerCode& c);
std::string emitControllerST(const ControllerCode& c);

}  // namespace mindyn::codegen
