// Generated generalised-momentum observer (mindyn/momentum_observer.hpp): one step per controller
// period beside the controller step, in C99 (a state struct, an init and an allocation-free step
// function, math.h only) and IEC 61131-3 Structured Text (one FUNCTION_BLOCK holding the state).
//
//   y = (p, beta)(q, dq; p_b): p = A(q) dq, beta = -dL/dq + friction + offset, by one momentum
//       pass over the links customised to the robot, with the base parameters as inputs;
//   first call (or reset): p(0) = p, integral = 0, r = 0;
//   then: s = integral + T tau_prev (held torque) or T/2 (tau + tau_prev) (sampled torque)
//             - T/2 (beta + beta_prev) + T/2 r_prev,
//         r = c (p - p(0) - s), c = K_O / (1 + K_O T/2),  integral = s + T/2 r,
// the same update as mindyn::MomentumObserver.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Core>
#include <string>

#include "mindyn/codegen/emit_c.hpp"
#include "mindyn/codegen/emit_st.hpp"
#include "mindyn/codegen/newton_euler.hpp"

namespace mindyn::codegen {

/// The settings a generated observer starts with.
struct ObserverSettings {
  Eigen::VectorXd gains;  // K_O per joint [1/s], 0 < K_O T < 2
  Eigen::VectorXd p;      // parameter values (size of the parameter set)
  double period = 0.004;
  bool held_torque = true;
};

struct ObserverCode {
  GeneratedCode code;  // one function: the momentum and beta products
  ObserverSettings settings;
  OpCount core;  // the momentum pass
  OpCount step;  // the whole step
};

/// The momentum pass alone: inputs q, dq and the parameters p; outputs p = A(q) dq (n entries)
/// then beta = -dL/dq + friction + offset (n entries), in the parameter set `params`.
GeneratedFunction generateMomentum(const Model& model, const ParameterSet& params);

/// Checks the settings (ModelError naming the one at fault) and generates the observer.
ObserverCode generateObserver(const Model& model, const ParameterSet& params,
                              const ObserverSettings& settings, const std::string& name);

/// C99 header and source: NAME_momentum_observer_t, _init, _step.
CFiles emitObserverC(const ObserverCode& c, const std::string& header_name,
                     CTrig trig = CTrig::Inline);

/// Structured Text: FUNCTION_BLOCK NAME_momentum_observer.
/// Its blocks (see STProgram), and their text writeST(observerProgramST(c)).
STProgram observerProgramST(const ObserverCode& c);
std::string emitObserverST(const ObserverCode& c);

}  // namespace mindyn::codegen
