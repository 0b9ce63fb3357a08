// The generated momentum observer (mindyn/codegen/observer.hpp): the momentum p = A(q) dq and
// beta = -dL/dq + friction + offset by one pass over the links (the formulas of
// mindyn/momentum.hpp: p_j = S_j . H_j, dK/dq_j = (v_j x S_j) . H_j with H_j the spatial momentum
// of link j and the links it carries, the gravity torque from the gravity wrenches carried the
// same way), written into an expression graph on the stages of every joint (stages.hpp) with the
// parameters as inputs; the observer update around it in C and Structured Text.
#include "mindyn/codegen/observer.hpp"

#include <cmath>
#include <sstream>
#include <utility>
#include <vector>

#include "builder.hpp"
#include "internal.hpp"

namespace mindyn::codegen {

namespace {

using internal::addCount;
using internal::AxisShift;
using internal::Builder;
using internal::JointStages;
using internal::jointStages;
using internal::M3;
using internal::openStepHeader;
using internal::P10;
using internal::Rigid;
using internal::V3;
using internal::Writer;

class MomentumBuilder : public Builder {
 public:
  using Builder::Builder;

  // Link velocities v and the gravity acceleration (zero velocities) of each link, in the frame
  // right after each joint motion (stage frame) and in the link frame.
  void forward(const std::vector<Ref>& dq) {
    Graph& g = graph();
    const int n = model_.nq();
    dq_ = dq;
    v_.assign(n, SV{});
    vs_.assign(n, SV{});
    ag_.assign(n, V3{});
    R_.assign(n, M3{});
    d_.assign(n, V3{});
    const SV base{zero_, zero_};
    V3 baseA;
    for (int i = 0; i < 3; ++i) baseA[i] = g.constant(-gravity_[i]);
    for (int k = 0; k < n; ++k) {
      const JointStages& s = stages_[k];
      const int parent = model_.parent(k);
      SV v = toChild(s.pre, parent < 0 ? base : v_[parent]);
      V3 a = rotateToChild(s.pre, parent < 0 ? baseA : ag_[parent]);
      const V3 u = constVec(s.u);
      if (s.type == JointType::Revolute) {
        const Ref angle = g.add(g.input(InputKind::Q, k), g.constant(s.offset));
        R_[k] = rodrigues(s.u, g.cos(angle), g.sin(angle));
        v = {mulT(R_[k], v.w), mulT(R_[k], v.l)};
        a = mulT(R_[k], a);
        v.w = addv(v.w, scale(u, dq[k]));
      } else {
        d_[k] = scale(u, g.input(InputKind::Q, k));
        v.l = addv(v.l, cross(v.w, d_[k]));
        v.l = addv(v.l, scale(u, dq[k]));
      }
      vs_[k] = v;
      v_[k] = toChild(s.post, v);
      ag_[k] = rotateToChild(s.post, a);
    }
  }

  // (p, beta) for classical parameters pi (layout `layout`).
  std::pair<std::vector<Ref>, std::vector<Ref>> momentum(const std::vector<Ref>& pi,
                                                         ParameterLayout layout) {
    Graph& g = graph();
    const int n = model_.nq();
    std::vector<Ref> p(n, Graph::zero()), beta(n, Graph::zero());
    std::vector<SV> childH(n, SV{zero_, zero_}), childG(n, SV{zero_, zero_});
    for (int k = n - 1; k >= 0; --k) {
      const JointStages& s = stages_[k];
      P10 par;
      for (int i = 0; i < 10; ++i) par[i] = pi[k * layout.perLink() + i];
      SV H = addsv(childH[k], inertia(par, v_[k]));
      SV G = addsv(childG[k], inertia(par, SV{zero_, ag_[k]}));
      H = toParent(s.post, H);
      G = toParent(s.post, G);
      const V3 u = constVec(s.u);
      const SV& v = vs_[k];
      Ref pk, dK, gk;
      if (s.type == JointType::Revolute) {
        pk = dot(u, H.w);
        dK = g.add(dot(cross(v.w, u), H.w), dot(cross(v.l, u), H.l));
        gk = dot(u, G.w);
      } else {
        pk = dot(u, H.l);
        dK = dot(cross(v.w, u), H.l);
        gk = dot(u, G.l);
      }
      p[k] = pk;
      beta[k] = g.add(gk, -dK);
      const int parent = model_.parent(k);
      if (parent < 0) continue;
      for (SV* x : {&H, &G}) {
        if (s.type == JointType::Revolute)
          *x = {mul(R_[k], x->w), mul(R_[k], x->l)};
        else
          x->w = addv(x->w, cross(d_[k], x->l));
        *x = toParent(s.pre, *x);
      }
      childH[parent] = addsv(childH[parent], H);
      childG[parent] = addsv(childG[parent], G);
    }
    // the rotors' momentum t_k Ia_k (t_k . dq) (their kinetic energy does not depend on q) and
    // the friction t_k f(t_k . dq) in beta
    internal::addDriveTerms(g, model_, pi, layout, dq_, p, dq_, beta);
    return {p, beta};
  }

 private:
  V3 rotateToChild(const Rigid& T, const V3& a) {
    if (T.R.isIdentity(0.0)) return a;
    return mulT(constMat(T.R), a);
  }

  std::vector<Ref> dq_;
  std::vector<SV> v_, vs_;
  std::vector<V3> ag_;
  std::vector<M3> R_;
  std::vector<V3> d_;
};

// The update after the momentum pass (y = p then beta), for a started observer.
void update(Writer& w, const ObserverCode& c) {
  const int n = c.code.n;
  const std::string T = w.scalar("period"), h = w.scalar("half");
  for (int k = 0; k < n; ++k) {
    const std::string torque =
        c.settings.held_torque ? T + " * " + w.field("tau_prev", k)
                               : h + " * (" + w.at("tau", k) + " + " + w.field("tau_prev", k) + ")";
    w.set("s", w.field("integral", k) + " + " + torque + " - " + h + " * (" + w.at("y", n + k) +
                   " + " + w.field("beta_prev", k) + ") + " + h + " * " + w.field("r", k));
    w.set(w.field("r", k),
          w.field("c", k) + " * (" + w.at("y", k) + " - " + w.field("p_start", k) + " - s)");
    w.set(w.field("integral", k), "s + " + h + " * " + w.field("r", k));
  }
}

// The state after the first sample (or a reset): p(0) = p, integral and r zero.
void start(Writer& w, const ObserverCode& c) {
  const int n = c.code.n;
  for (int k = 0; k < n; ++k) {
    w.set(w.field("p_start", k), w.at("y", k));
    w.set(w.field("integral", k), "0.0");
    w.set(w.field("r", k), "0.0");
  }
}

void carry(Writer& w, const ObserverCode& c) {
  const int n = c.code.n;
  for (int k = 0; k < n; ++k) {
    w.set(w.field("tau_prev", k), w.at("tau", k));
    w.set(w.field("beta_prev", k), w.at("y", n + k));
    w.set(w.at("r_out", k), w.field("r", k));
  }
}

std::vector<std::string> header(const ObserverCode& c) {
  const int n = c.code.n, np = c.code.params.size();
  const ParameterSet& ps = c.code.params;
  std::vector<std::string> out;
  out.push_back("Generated by mindyn from robot '" + c.code.robot + "' (" + std::to_string(n) +
                " joints).");
  out.push_back("");
  std::vector<std::string> extras;
  if (ps.layout.rotor) extras.push_back("rotor inertia");
  if (ps.layout.friction) extras.push_back(internal::frictionWords(c.code.friction.kind));
  if (ps.offsets) extras.push_back("a torque offset per joint");
  out.push_back("Generalised-momentum observer of external joint torques in the " +
                std::to_string(np) + (ps.base ? " base" : " classical") + " parameters p" +
                (extras.empty() ? ":" : ","));
  if (!extras.empty()) {
    std::string with = "with ";
    for (size_t i = 0; i < extras.size(); ++i)
      with += (i ? (i + 1 == extras.size() ? " and " : ", ") : "") + extras[i];
    out.push_back(with + ":");
  }
  out.push_back("  r = K_O (p(t) - p(0) - int (tau - beta + r) dt), p = A(q) dq,");
  out.push_back("  beta = -dL/dq + friction + offset (= g - C^T dq + ...), no accelerations.");
  out.push_back("Discrete at the period T: the integral advances by " +
                std::string(c.settings.held_torque ? "T tau_prev (the torque held)"
                                                   : "T/2 (tau + tau_prev)") +
                ",");
  out.push_back("  - T/2 (beta + beta_prev) + T/2 (r + r_prev), r solved from its own term:");
  out.push_back("  r = c (p - p(0) - s), c = K_O / (1 + K_O T/2): the bilinear image of");
  out.push_back("  K_O / (s + K_O) acting on the external torque. The first call (or reset) sets");
  out.push_back("  p(0) and returns r = 0.");
  std::string per = "Per step: " + std::to_string(c.step.mul) + " mul, " +
                    std::to_string(c.step.add) + " add, " + std::to_string(c.step.trig) +
                    " sin/cos";
  for (const auto& [count, what] : {std::pair{c.step.sign, " sign"},
                                    std::pair{c.step.tanh, " tanh"}, std::pair{c.step.exp, " exp"}})
    if (count) per += ", " + std::to_string(count) + what;
  out.push_back(per + " (momentum pass: " + std::to_string(c.core.mul) + " mul, " +
                std::to_string(c.core.add) + " add).");
  out.push_back("Units SI; gravity and all frames as in the robot description.");
  const std::vector<std::string> drive = internal::driveLines(c.code);
  out.insert(out.end(), drive.begin(), drive.end());
  if (!drive.empty()) {
    const bool m = c.code.motor_side;
    std::string l = "In the observer:";
    if (ps.layout.rotor) l += m ? " p += T^T Ia T dq" : " p += Ia dq";
    if (ps.layout.friction)
      l += std::string(ps.layout.rotor ? "," : "") +
           (m ? " beta += T^T friction(T dq)" : " beta += friction(dq)");
    out.push_back(l + ".");
  }
  return out;
}

}  // namespace

GeneratedFunction generateMomentum(const Model& model, const ParameterSet& params) {
  requireSingleDof(model, "a generated momentum observer");
  const int n = model.nq(), np = params.size(), P = params.layout.size(n);
  if (params.E.rows() != P || params.E.cols() != np)
    throw ModelError("codegen: the parameter map does not fit the model");
  if (params.offsets != 0 && params.offsets != n)
    throw ModelError("codegen: " + std::to_string(params.offsets) + " torque offsets for " +
                     std::to_string(n) + " joints");
  internal::checkDriveTerms(model, params.layout);
  const int off0 = np - params.offsets;
  GeneratedFunction out;
  out.function = Function::SlotineLi;  // emitted through the step's own writers only
  out.n = n;
  out.np = np;
  Graph& g = out.graph;
  MomentumBuilder b(g, model, jointStages(model, std::vector<AxisShift>(n, AxisShift::Keep)));
  std::vector<Ref> dq(n);
  for (int k = 0; k < n; ++k) dq[k] = g.input(InputKind::DQ, k);
  b.forward(dq);
  std::vector<Ref> p(np);
  for (int j = 0; j < np; ++j) p[j] = g.input(InputKind::P, j);
  std::vector<Ref> pi(P, Graph::zero());
  for (int col = 0; col < P; ++col)
    for (int j = 0; j < off0; ++j)
      if (params.E(col, j) != 0.0)
        pi[col] = g.add(pi[col], g.mul(g.constant(params.E(col, j)), p[j]));
  auto [mom, beta] = b.momentum(pi, params.layout);
  for (int k = 0; k < params.offsets; ++k) beta[k] = g.add(beta[k], p[off0 + k]);
  out.outputs = mom;
  out.outputs.insert(out.outputs.end(), beta.begin(), beta.end());
  out.program = schedule(g, out.outputs);
  jointStages(model, std::vector<AxisShift>(n, AxisShift::Keep), &out.snap);
  internal::cleanGeometry<3, 1>(model.gravity, false, &out.snap);
  return out;
}

ObserverCode generateObserver(const Model& model, const ParameterSet& params,
                              const ObserverSettings& settings, const std::string& name) {
  checkIdentifier(name);
  const int n = model.nq(), np = params.size();
  ObserverSettings s = settings;
  if (s.p.size() == 0) s.p = params.values;
  if (!(std::isfinite(s.period) && s.period > 0))
    throw ModelError("observer setting 'period' is " + literal(s.period) +
                     "; expected a finite number of seconds > 0");
  if (s.p.size() != np || !s.p.allFinite())
    throw ModelError("observer setting 'p' must be " + std::to_string(np) + " finite values");
  if (s.gains.size() == 0) s.gains = Eigen::VectorXd::Constant(n, 1.0 / (10.0 * s.period));
  if (s.gains.size() != n)
    throw ModelError("observer setting 'gains' has " + std::to_string(s.gains.size()) +
                     " values; expected " + std::to_string(n));
  for (int k = 0; k < n; ++k)
    if (!(s.gains[k] > 0 && s.gains[k] * s.period < 2.0))
      throw ModelError("observer gain K_O of joint " + std::to_string(k + 1) + " is " +
                       literal(s.gains[k]) +
                       "; expected 0 < K_O < 2 / period = " + literal(2.0 / s.period));
  ObserverCode c;
  c.settings = s;
  GeneratedCode& code = c.code;
  describeModel(code, model);
  code.name = name;
  code.params = params;
  code.values = s.p;
  code.functions.push_back(generateMomentum(model, params));
  c.core = code.functions.front().program.count;
  c.step = c.core;
  // per joint: s (3 mul; 4 add, 5 with the sampled torque), r (1 mul, 2 add), the integral
  // (1 mul, 1 add)
  addCount(c.step, 5L * n, (s.held_torque ? 7L : 8L) * n);
  return c;
}

CFiles emitObserverC(const ObserverCode& c, const std::string& header_name, CTrig trig) {
  const std::string fn = c.code.name + "_momentum_observer", T = fn + "_t";
  const int n = c.code.n, np = c.code.params.size();
  const GeneratedFunction& f = c.code.functions.front();
  const std::string N = std::to_string(n), NP = std::to_string(np);
  std::ostringstream h, src;
  openStepHeader(h, fn, header(c), n, np);
  h << "/* Settings (set by " << fn << "_init to the generated values; they may be changed\n"
    << " * before a reset): p the parameters, ko the gains K_O [1/s], period [s], with\n"
    << " * c = ko / (1 + ko period / 2) and half = period / 2 derived from them. State: started,\n"
    << " * p_start = p(0), integral, r, tau_prev, beta_prev. */\n";
  h << "typedef struct {\n  double p[" << NP << "];\n  double ko[" << N << "];\n  double c[" << N
    << "];\n  double period;\n  double half;\n  int started;\n";
  for (const char* s : {"p_start", "integral", "r", "tau_prev", "beta_prev"})
    h << "  double " << s << "[" << N << "];\n";
  h << "} " << T << ";\n\n";
  h << "/* The generated settings; the next step starts the observer. */\n";
  h << "void " << fn << "_init(" << T << "* c);\n";
  h << "/* Restarts the observer at the next step (after a change of settings). */\n";
  h << "void " << fn << "_reset(" << T << "* c);\n";
  h << "/* One period: measured q, dq and the torque tau -> the residual r_out. */\n";
  h << "void " << fn << "_step(" << T << "* c, const double q[" << N << "], const double dq[" << N
    << "],\n    const double tau[" << N << "], double r_out[" << N << "]);\n";
  h << "\n#ifdef __cplusplus\n}\n#endif\n\n#endif\n";

  src << "/* " << header_name << ": see the header. */\n#include \"" << header_name
      << "\"\n\n#include <math.h>\n";
  if (trig == CTrig::Inline && internal::usesTrig(f)) src << "\n" << internal::sincosSource(fn);
  Writer init{false, {}, "  "};
  for (int j = 0; j < np; ++j) init.set(init.field("p", j), literal(c.settings.p[j]));
  for (int k = 0; k < n; ++k) init.set(init.field("ko", k), literal(c.settings.gains[k]));
  init.set("c->period", literal(c.settings.period));
  src << "\nvoid " << fn << "_reset(" << T << "* c) {\n  int k;\n"
      << "  c->half = 0.5 * c->period;\n"
      << "  for (k = 0; k < " << N << "; ++k) c->c[k] = c->ko[k] / (1.0 + c->half * c->ko[k]);\n"
      << "  c->started = 0;\n}\n";
  src << "\nvoid " << fn << "_init(" << T << "* c) {\n"
      << init.os.str() << "  " << fn << "_reset(c);\n}\n";
  std::ostringstream body;
  internal::writeCBody(body, f, fn, trig, "y");
  Writer first{false, {}, "    "}, rest{false, {}, "    "}, tail{false, {}, "  "};
  start(first, c);
  update(rest, c);
  carry(tail, c);
  src << "\nvoid " << fn << "_step(" << T << "* c, const double q[" << N << "], const double dq["
      << N << "],\n    const double tau[" << N << "], double r_out[" << N << "]) {\n";
  src << "  const double* const p = c->p;\n  double y[" << 2 * n << "];\n  double s;\n";
  src << "  /* momentum pass: " << c.core.mul << " mul, " << c.core.add << " add, " << c.core.trig
      << " sin/cos */\n";
  src << body.str();
  src << "  if (!c->started) {\n"
      << first.os.str() << "    c->started = 1;\n  } else {\n"
      << rest.os.str() << "  }\n"
      << tail.os.str() << "  (void)s;\n}\n";
  return {h.str(), src.str()};
}

STProgram observerProgramST(const ObserverCode& c) {
  using internal::stScalar;
  const int n = c.code.n, np = c.code.params.size();
  const GeneratedFunction& f = c.code.functions.front();
  const auto vecN = [n](const std::string& name) { return internal::stVector(name, n); };
  STProgram p;
  p.comments = header(c);
  p.comments.push_back(
      "Arrays are 1-based: q[k] is joint k, p[j] parameter j. The settings are set on the\n"
      "   first call and when reset is TRUE, which also restarts the observer.");
  STFunctionBlock b;
  b.name = c.code.name + "_momentum_observer";
  for (const char* v : {"q", "dq", "tau"}) b.inputs.push_back(vecN(v));
  b.inputs.push_back(stScalar("reset", "BOOL"));
  b.outputs.push_back(vecN("r_out"));
  b.locals.push_back(internal::stVector("p", np));
  b.locals.push_back(vecN("ko"));
  b.locals.push_back(vecN("c"));
  for (const char* v : {"period", "half", "s"}) b.locals.push_back(stScalar(v));
  b.locals.push_back(stScalar("initialised", "BOOL"));
  b.locals.push_back(stScalar("started", "BOOL"));
  for (const char* v : {"p_start", "integral", "r", "tau_prev", "beta_prev"})
    b.locals.push_back(vecN(v));
  b.locals.push_back(internal::stVector("y", 2 * n));
  std::ostringstream body;
  const int slots = internal::writeSTBody(body, f, "y");
  for (int t = 0; t < slots; ++t) b.locals.push_back(stScalar("t" + std::to_string(t + 1)));
  Writer init{true, {}, "  "};
  for (int j = 0; j < np; ++j) init.set(init.field("p", j), literal(c.settings.p[j], true));
  for (int k = 0; k < n; ++k) init.set(init.field("ko", k), literal(c.settings.gains[k], true));
  init.set("period", literal(c.settings.period, true));
  init.set("half", "0.5 * period");
  for (int k = 0; k < n; ++k)
    init.set(init.field("c", k),
             init.field("ko", k) + " / (1.0 + half * " + init.field("ko", k) + ")");
  init.set("started", "FALSE");
  init.set("initialised", "TRUE");
  Writer first{true, {}, "  "}, rest{true, {}, "  "}, tail{true, {}, ""};
  start(first, c);
  update(rest, c);
  carry(tail, c);
  b.body = "IF reset OR NOT initialised THEN\n" + init.os.str() + "END_IF;\n" + body.str() +
           "IF NOT started THEN\n" + first.os.str() + "  started := TRUE;\nELSE\n" + rest.os.str() +
           "END_IF;\n" + tail.os.str();
  p.blocks.push_back(std::move(b));
  return p;
}

std::string emitObserverST(const ObserverCode& c) { return writeST(observerProgramST(c)); }

}  // namespace mindyn::codegen
