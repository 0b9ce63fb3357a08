#include "mindyn/codegen/controller.hpp"

#include <cmath>
#include <functional>
#include <sstream>
#include <utility>

#include "internal.hpp"
#include "mindyn/codegen/emit_st.hpp"

namespace mindyn::codegen {

const char* toString(Controller c) {
  switch (c) {
    case Controller::AdaptivePD:
      return "adaptive_pd";
    case Controller::ComputedTorque:
      return "computed_torque";
    case Controller::GravityCompensation:
      return "gravity_compensation";
  }
  return "?";
}

namespace {

using internal::addCount;
using internal::openStepHeader;
using internal::Writer;

// A setting vector: `size` finite entries >= 0 (or any finite value when `signed_`), infinite
// allowed when `infinite`.
void check(const Eigen::VectorXd& v, long size, const char* name, bool signed_ = false,
           bool infinite = false) {
  if (v.size() != size)
    throw ModelError("controller setting '" + std::string(name) + "' has " +
                     std::to_string(v.size()) + " values; expected " + std::to_string(size));
  for (long i = 0; i < size; ++i) {
    const double x = v[i];
    if (std::isnan(x) || (!infinite && !std::isfinite(x)) || (!signed_ && x < 0))
      throw ModelError("controller setting '" + std::string(name) + "': entry " +
                       std::to_string(i + 1) + " is " + literal(x) + "; expected a finite " +
                       (signed_ ? "number" : "number >= 0") + (infinite ? " or infinity" : ""));
  }
}

struct Field {
  const char* name;
  bool perParameter;  // np entries, else n
  const Eigen::VectorXd* values;
};

std::vector<Field> fields(const ControllerCode& c) {
  const ControllerSettings& s = c.settings;
  std::vector<Field> f;
  f.push_back({"p0", true, &s.p0});
  f.push_back({"kd", false, &s.kd});
  if (c.kind == Controller::AdaptivePD) {
    f.push_back({"lambda", false, &s.lambda});
    f.push_back({"gamma", true, &s.gamma});
    f.push_back({"p_min", true, &s.p_min});
    f.push_back({"p_max", true, &s.p_max});
  } else {
    f.push_back({"kp", false, &s.kp});
  }
  f.push_back({"tau_max", false, &s.tau_max});
  return f;
}

bool normalised(const ControllerCode& c) {
  return c.kind == Controller::AdaptivePD && c.settings.nu > 0;
}

// The step after the settings: the terms before the dynamics function, its body (outputs in y),
// the terms after. Arguments q, dq, q_d, dq_d, ddq_d, tau; the estimate p.
void stepBody(Writer& w, const ControllerCode& c, const std::string& prefix, CTrig trig) {
  const int n = c.code.n, np = c.code.params.size();
  const GeneratedFunction& f = c.code.functions.front();
  for (int k = 0; k < n; ++k) {
    w.set(w.at("e", k), w.at("q", k) + " - " + w.at("q_d", k));
    if (c.kind == Controller::GravityCompensation) continue;
    w.set(w.at("de", k), w.at("dq", k) + " - " + w.at("dq_d", k));
    if (c.kind == Controller::AdaptivePD) {
      w.set(w.at("le", k), w.field("lambda", k) + " * " + w.at("e", k));
      w.set(w.at("dqr", k), w.at("dq_d", k) + " - " + w.at("le", k));
      w.set(w.at("ddqr", k),
            w.at("ddq_d", k) + " - " + w.field("lambda", k) + " * " + w.at("de", k));
      w.set(w.at("s", k), w.at("de", k) + " + " + w.at("le", k));
    } else {
      w.set(w.at("ddq", k), w.at("ddq_d", k) + " - " + w.field("kd", k) + " * " + w.at("de", k) +
                                " - " + w.field("kp", k) + " * " + w.at("e", k));
    }
  }
  if (c.kind == Controller::GravityCompensation)
    for (int k = 0; k < n; ++k) w.set(w.at("de", k), w.at("dq", k) + " - " + w.at("dq_d", k));
  w.comment(std::string(toString(f.function)) + ": " + std::to_string(c.core.mul) + " mul, " +
            std::to_string(c.core.add) + " add, " + std::to_string(c.core.trig) + " sin/cos");
  std::ostringstream body;
  if (w.st)
    internal::writeSTBody(body, f, "y");
  else
    internal::writeCBody(body, f, prefix, trig, "y");
  w.os << body.str();
  for (int k = 0; k < n; ++k) {
    std::string tau = w.at("y", k);
    if (c.kind == Controller::AdaptivePD) tau += " - " + w.field("kd", k) + " * " + w.at("s", k);
    if (c.kind == Controller::GravityCompensation)
      tau += " - " + w.field("kp", k) + " * " + w.at("e", k) + " - " + w.field("kd", k) + " * " +
             w.at("de", k);
    w.set(w.at("tau", k), tau);
    w.clamp(w.at("tau", k), "-" + w.field("tau_max", k), w.field("tau_max", k));
  }
  if (c.kind != Controller::AdaptivePD) return;
  w.comment("adaptation over one period, the estimate kept in its box");
  if (normalised(c)) w.set("den", "1.0 + " + w.scalar("nu") + " * " + w.at("y", n + np));
  for (int j = 0; j < np; ++j) {
    std::string step = w.scalar("period") + " * " + w.field("gamma", j) + " * " + w.at("y", n + j);
    if (normalised(c)) step = "(" + step + ") / den";
    w.set(w.field("p", j), w.field("p", j) + " - " + step);
    w.clamp(w.field("p", j), w.field("p_min", j), w.field("p_max", j));
  }
}

std::vector<std::string> header(const ControllerCode& c) {
  std::vector<std::string> lines = describe(c.code);
  std::vector<std::string> out(lines.begin(), lines.begin() + 1);
  const int n = c.code.n, np = c.code.params.size();
  out.push_back("");
  switch (c.kind) {
    case Controller::AdaptivePD:
      out.push_back("Slotine-Li adaptive controller (adaptive PD) in the " + std::to_string(np) +
                    " parameters p:");
      out.push_back(
          "  e = q - q_d, de = dq - dq_d, dqr = dq_d - lambda e, ddqr = ddq_d - lambda de,");
      out.push_back("  s = de + lambda e, tau = Y(q, dq, dqr, ddqr) p - kd s (within +-tau_max),");
      out.push_back(
          normalised(c)
              ? "  p <- p - period gamma Y^T s / (1 + nu |Y|^2), then clamped to [p_min, p_max]."
              : "  p <- p - period gamma Y^T s, then clamped to [p_min, p_max].");
      out.push_back("Y p and Y^T s from the Slotine-Li recursion customised to the robot:");
      out.push_back("  " + std::string(toString(c.form)) + " (all forms counted below).");
      break;
    case Controller::ComputedTorque:
      out.push_back("Computed torque in the " + std::to_string(np) +
                    " parameters p: tau = ID(q, dq, ddq_d - kd de - kp e) p");
      out.push_back("(within +-tau_max), e = q - q_d, de = dq - dq_d.");
      break;
    case Controller::GravityCompensation:
      out.push_back("PD with gravity compensation in the " + std::to_string(np) +
                    " parameters p: tau = g(q) p - kp e - kd de");
      out.push_back("(within +-tau_max), e = q - q_d, de = dq - dq_d.");
      break;
  }
  std::string per = "Per step: " + std::to_string(c.step.mul) + " mul, " +
                    std::to_string(c.step.add) + " add, " + std::to_string(c.step.trig) +
                    " sin/cos";
  for (const auto& [count, what] :
       {std::pair{c.step.sign, " sign"}, std::pair{c.step.tanh, " tanh"},
        std::pair{c.step.exp, " exp"}, std::pair{static_cast<long>(c.divisions), " div"}})
    if (count) per += ", " + std::to_string(count) + what;
  out.push_back(per + " (" + std::to_string(n) + " joints, " + std::to_string(np) +
                " parameters).");
  for (const auto& v : c.variants)
    out.push_back("  " + std::string(toString(v.form)) + ": " + std::to_string(v.count.mul) +
                  " mul, " + std::to_string(v.count.add) + " add");
  out.push_back("Infinite bounds are written as +-1e300.");
  out.insert(out.end(), lines.begin() + 1, lines.end());
  return out;
}

}  // namespace

ControllerCode generateController(const Model& model, const ParameterSet& params, Controller kind,
                                  const ControllerSettings& settings, const std::string& name) {
  checkIdentifier(name);
  requireSingleDof(model, "a generated controller");
  const int n = model.nq(), np = params.size();
  ControllerSettings s = settings;
  if (s.p0.size() == 0) s.p0 = params.values;
  check(s.p0, np, "p0", true);
  check(s.kd, n, "kd");
  if (s.tau_max.size() == 0) s.tau_max = Eigen::VectorXd::Constant(n, INFINITY);
  check(s.tau_max, n, "tau_max", false, true);
  if (!(std::isfinite(s.period) && s.period > 0))
    throw ModelError("controller setting 'period' is " + literal(s.period) +
                     "; expected a finite number of seconds > 0");
  if (kind == Controller::AdaptivePD) {
    check(s.lambda, n, "lambda");
    check(s.gamma, np, "gamma");
    if (s.p_min.size() == 0) s.p_min = Eigen::VectorXd::Constant(np, -INFINITY);
    if (s.p_max.size() == 0) s.p_max = Eigen::VectorXd::Constant(np, INFINITY);
    check(s.p_min, np, "p_min", true, true);
    check(s.p_max, np, "p_max", true, true);
    for (int j = 0; j < np; ++j)
      if (!(s.p_min[j] <= s.p0[j] && s.p0[j] <= s.p_max[j]))
        throw ModelError("controller setting 'p0': entry " + std::to_string(j + 1) + " (" +
                         params.names[j] + " = " + literal(s.p0[j]) + ") is outside [p_min, " +
                         "p_max] = [" + literal(s.p_min[j]) + ", " + literal(s.p_max[j]) + "]");
    if (!(std::isfinite(s.nu) && s.nu >= 0))
      throw ModelError("controller setting 'nu' is " + literal(s.nu) +
                       "; expected a finite number >= 0");
  } else {
    check(s.kp, n, "kp");
  }
  ControllerCode c;
  c.kind = kind;
  c.settings = s;
  GeneratedCode& code = c.code;
  describeModel(code, model);
  code.name = name;
  code.params = params;
  code.values = s.p0;
  if (kind == Controller::AdaptivePD)
    code.functions.push_back(generateSlotineLi(model, params, s.nu > 0, &c.variants));
  else
    code.functions.push_back(generate(
        model, params,
        kind == Controller::ComputedTorque ? Function::InverseDynamics : Function::Gravity));
  c.core = code.functions.front().program.count;
  for (const auto& v : c.variants)
    if (v.count.mul == c.core.mul && v.count.add == c.core.add) c.form = v.form;
  c.step = c.core;
  if (kind == Controller::AdaptivePD) {
    addCount(c.step, 2L * n, 5L * n);  // e, de, lambda e, dqr, ddqr, s
    addCount(c.step, n, n);            // tau
    addCount(c.step, 2L * np, np);     // the adaptation step
    if (s.nu > 0) {
      addCount(c.step, 1, 1);
      c.divisions = np;
    }
  } else {
    addCount(c.step, 2L * n, 4L * n);  // e, de and the PD terms
  }
  return c;
}

CFiles emitControllerC(const ControllerCode& c, const std::string& header_name, CTrig trig) {
  const std::string kind = toString(c.kind);
  const std::string fn = c.code.name + "_" + kind, T = fn + "_t";
  const int n = c.code.n, np = c.code.params.size();
  const GeneratedFunction& f = c.code.functions.front();
  const std::string N = std::to_string(n), NP = std::to_string(np);
  std::ostringstream h, src;
  openStepHeader(h, fn, header(c), n, np);
  h << "/* Settings and state: set by " << fn << "_init to the generated values; the settings\n"
    << " * may be changed between steps. p is the estimate (p0 its initial value). */\n";
  h << "typedef struct {\n  double p[" << NP << "];\n";
  for (const Field& fd : fields(c))
    h << "  double " << fd.name << "[" << (fd.perParameter ? NP : N) << "];\n";
  if (normalised(c)) h << "  double nu;\n";
  if (c.kind == Controller::AdaptivePD) h << "  double period; /* s */\n";
  h << "} " << T << ";\n\n";
  h << "/* The generated settings, and p = p0. */\n";
  h << "void " << fn << "_init(" << T << "* c);\n";
  h << "/* One controller period: measured q, dq, desired q_d, dq_d, ddq_d -> tau. */\n";
  h << "void " << fn << "_step(" << T << "* c, const double q[" << N << "], const double dq[" << N
    << "],\n    const double q_d[" << N << "], const double dq_d[" << N << "], const double ddq_d["
    << N << "], double tau[" << N << "]);\n";
  h << "\n#ifdef __cplusplus\n}\n#endif\n\n#endif\n";

  src << "/* " << header_name << ": see the header. */\n#include \"" << header_name
      << "\"\n\n#include <math.h>\n";
  if (trig == CTrig::Inline && internal::usesTrig(f))
    src << "\n" << internal::sincosSource(c.code.name + "_" + kind);
  Writer w{false, {}, "  "};
  src << "\nvoid " << fn << "_init(" << T << "* c) {\n";
  for (const Field& fd : fields(c))
    for (long i = 0; i < fd.values->size(); ++i) w.set(w.field(fd.name, i), w.num((*fd.values)[i]));
  if (normalised(c)) w.set("c->nu", w.num(c.settings.nu));
  if (c.kind == Controller::AdaptivePD) w.set("c->period", w.num(c.settings.period));
  for (int j = 0; j < np; ++j) w.set(w.field("p", j), w.field("p0", j));
  src << w.os.str() << "}\n";
  Writer s{false, {}, "  "};
  stepBody(s, c, fn, trig);
  src << "\nvoid " << fn << "_step(" << T << "* c, const double q[" << N << "], const double dq["
      << N << "],\n    const double q_d[" << N << "], const double dq_d[" << N
      << "], const double ddq_d[" << N << "], double tau[" << N << "]) {\n";
  src << "  const double* const p = c->p;\n";
  const int ny = static_cast<int>(f.outputs.size());
  src << "  double e[" << N << "], de[" << N << "], y[" << ny << "];\n";
  if (c.kind == Controller::AdaptivePD)
    src << "  double le[" << N << "], dqr[" << N << "], ddqr[" << N << "], s[" << N << "];\n";
  if (c.kind == Controller::ComputedTorque) src << "  double ddq[" << N << "];\n";
  if (normalised(c)) src << "  double den;\n";
  if (c.kind == Controller::GravityCompensation) src << "  (void)ddq_d;\n";
  src << s.os.str() << "}\n";
  return {h.str(), src.str()};
}

STProgram controllerProgramST(const ControllerCode& c) {
  using internal::stScalar;
  const std::string kind = toString(c.kind);
  const int n = c.code.n, np = c.code.params.size();
  const GeneratedFunction& f = c.code.functions.front();
  const auto vecN = [n](const std::string& name) { return internal::stVector(name, n); };
  STProgram p;
  p.comments = header(c);
  p.comments.push_back(
      "Arrays are 1-based: q[k] is joint k, p[j] parameter j. The settings are set on the\n"
      "   first call and when reset is TRUE, which also sets the estimate p back to p0.");
  STFunctionBlock b;
  b.name = c.code.name + "_" + kind;
  for (const char* v : {"q", "dq", "q_d", "dq_d", "ddq_d"}) b.inputs.push_back(vecN(v));
  b.inputs.push_back(stScalar("reset", "BOOL"));
  b.outputs.push_back(vecN("tau"));
  b.locals.push_back(internal::stVector("p", np));
  for (const Field& fd : fields(c))
    b.locals.push_back(fd.perParameter ? internal::stVector(fd.name, np) : vecN(fd.name));
  if (normalised(c)) {
    b.locals.push_back(stScalar("nu"));
    b.locals.push_back(stScalar("den"));
  }
  if (c.kind == Controller::AdaptivePD) b.locals.push_back(stScalar("period"));
  b.locals.push_back(stScalar("initialised", "BOOL"));
  b.locals.push_back(vecN("e"));
  b.locals.push_back(vecN("de"));
  if (c.kind == Controller::AdaptivePD)
    for (const char* v : {"le", "dqr", "ddqr", "s"}) b.locals.push_back(vecN(v));
  if (c.kind == Controller::ComputedTorque) b.locals.push_back(vecN("ddq"));
  b.locals.push_back(internal::stVector("y", static_cast<int>(f.outputs.size())));
  std::ostringstream probe;
  const int slots = internal::writeSTBody(probe, f, "y");
  for (int t = 0; t < slots; ++t) b.locals.push_back(stScalar("t" + std::to_string(t + 1)));
  Writer s{true, {}, ""};
  stepBody(s, c, b.name, CTrig::Libm);
  Writer init{true, {}, "  "};
  for (const Field& fd : fields(c))
    for (long i = 0; i < fd.values->size(); ++i)
      init.set(init.field(fd.name, i), init.num((*fd.values)[i]));
  if (normalised(c)) init.set("nu", init.num(c.settings.nu));
  if (c.kind == Controller::AdaptivePD) init.set("period", init.num(c.settings.period));
  for (int j = 0; j < np; ++j) init.set(init.field("p", j), init.field("p0", j));
  init.set("initialised", "TRUE");
  b.body = "IF reset OR NOT initialised THEN\n" + init.os.str() + "END_IF;\n" + s.os.str();
  p.blocks.push_back(std::move(b));
  return p;
}

std::string emitControllerST(const ControllerCode& c) { return writeST(controllerProgramST(c)); }

}  // namespace mindyn::codegen
