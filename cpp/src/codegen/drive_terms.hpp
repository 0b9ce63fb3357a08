// The rotor inertia and friction of a parameter layout's slots written into an expression graph:
// the one place the generated code forms them (inverse dynamics, regressor, Slotine-Li and
// controller steps, momentum observer). Slot k acts on joint k, or, when the model's
// motorSide(), on motor k: with t_k row k of T (e_k on the joints), the slot's acceleration
// a_k = t_k . acc and velocity v_k = t_k . vel are formed once (zero entries of T skipped,
// entries of +-1 without a product), its rotor torque Ia_k a_k and friction torque f(v_k)
// (frictionTorque) taken back to the joints by t_k^T.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "mindyn/codegen/expr.hpp"
#include "mindyn/model.hpp"

namespace mindyn::codegen::internal {

// Throws ModelError unless the model can carry the layout's rotor inertia and friction: on the
// motors (Model::motorSide()) one motor per slot, and with friction as many friction columns as
// the model's friction model has, with a velocity scale per slot where it needs one.
inline void checkDriveTerms(const Model& model, ParameterLayout layout) {
  const int n = model.nq();
  if (model.motorSide() && (layout.rotor || layout.friction) && model.transmission.nm() != n)
    throw ModelError(
        "codegen: rotor inertia and friction on the motors need one motor per "
        "joint; " +
        model.name + " has " + std::to_string(model.transmission.nm()) + " motors for " +
        std::to_string(n) + " joints (put them on the joints)");
  if (!layout.friction) return;
  const FrictionModel& fm = model.friction_model;
  if (layout.friction_columns != fm.columns())
    throw ModelError("codegen: the parameters have " + std::to_string(layout.friction_columns) +
                     " friction columns per joint; the friction model of " + model.name + " has " +
                     std::to_string(fm.columns()));
  const bool scaled = fm.kind == FrictionKind::Smooth || fm.kind == FrictionKind::Stribeck;
  if (scaled && fm.velocity.size() != n)
    throw ModelError("codegen: the friction model needs a velocity scale per joint (" +
                     std::to_string(n) + "), it has " + std::to_string(fm.velocity.size()));
}

// The friction torque of slot k at its velocity v, with f = (Fv, Fc, third parameter) and the
// friction model fm (w_k its velocity scale, baked in as 1 / w_k):
//   Coulomb Fv v + Fc sign(v); Asymmetric + Fa |sign(v)| (as sign(v) sign(v));
//   Smooth Fv v + Fc tanh(v / w_k); Stribeck Fv v + Fc sign(v) + Fs sign(v) exp(-(v / w_k)^2).
inline Ref frictionTorque(Graph& g, const FrictionModel& fm, const std::array<Ref, 3>& f, int k,
                          Ref v) {
  Ref t = g.mul(f[0], v);
  if (fm.kind == FrictionKind::Smooth) {
    const Ref x = g.mul(g.constant(1.0 / fm.velocity[k]), v);
    return g.add(t, g.mul(f[1], g.tanh(x)));
  }
  const Ref s = g.sign(v);
  t = g.add(t, g.mul(f[1], s));
  if (f[2] == Graph::zero()) return t;
  if (fm.kind == FrictionKind::Asymmetric) return g.add(t, g.mul(f[2], g.mul(s, s)));
  const Ref x = g.mul(g.constant(1.0 / fm.velocity[k]), v);
  return g.add(t, g.mul(f[2], g.mul(s, g.exp(-g.mul(x, x)))));
}

// Adds the layout's drive terms of the classical parameters `pi` to joint torques:
// sum_k t_k Ia_k (t_k . acc) to `rotor_out` and sum_k t_k f_k(t_k . vel) to `friction_out`.
// When both are the same vector, each slot's two torques are summed and taken back once. The
// momentum observer puts them apart: its momentum gets Ia_k t_k (t_k . dq), its beta the friction.
inline void addDriveTerms(Graph& g, const Model& model, const std::vector<Ref>& pi,
                          ParameterLayout layout, const std::vector<Ref>& acc,
                          std::vector<Ref>& rotor_out, const std::vector<Ref>& vel,
                          std::vector<Ref>& friction_out) {
  if (!layout.rotor && !layout.friction) return;
  const int n = model.nq();
  const bool motors = model.motorSide();
  const bool together = &rotor_out == &friction_out;
  auto slotSum = [&](int k, const std::vector<Ref>& x) {
    if (!motors) return x[k];
    Ref s = Graph::zero();
    for (int j = 0; j < n; ++j)
      if (model.transmission.T(k, j) != 0.0)
        s = g.add(s, g.mul(g.constant(model.transmission.T(k, j)), x[j]));
    return s;
  };
  auto toJoints = [&](int k, Ref t, std::vector<Ref>& out) {
    if (t == Graph::zero()) return;
    if (!motors) {
      out[k] = g.add(out[k], t);
      return;
    }
    for (int j = 0; j < n; ++j)
      if (model.transmission.T(k, j) != 0.0)
        out[j] = g.add(out[j], g.mul(g.constant(model.transmission.T(k, j)), t));
  };
  for (int k = 0; k < n; ++k) {
    const Ref ia = layout.rotor ? pi[layout.rotorIndex(k)] : Graph::zero();
    std::array<Ref, 3> f{Graph::zero(), Graph::zero(), Graph::zero()};
    if (layout.friction) {
      f[0] = pi[layout.viscousIndex(k)];
      f[1] = pi[layout.coulombIndex(k)];
      if (layout.friction_columns == 3) f[2] = pi[layout.thirdFrictionIndex(k)];
    }
    Ref rotor = Graph::zero(), friction = Graph::zero();
    if (ia != Graph::zero()) rotor = g.mul(ia, slotSum(k, acc));
    if (f[0] != Graph::zero() || f[1] != Graph::zero() || f[2] != Graph::zero())
      friction = frictionTorque(g, model.friction_model, f, k, slotSum(k, vel));
    if (together) {
      toJoints(k, g.add(rotor, friction), rotor_out);
    } else {
      toJoints(k, rotor, rotor_out);
      toJoints(k, friction, friction_out);
    }
  }
}

}  // namespace mindyn::codegen::internal
