#include "mindyn/codegen/newton_euler.hpp"

#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <utility>

namespace mindyn::codegen {

namespace {

using V3 = std::array<Ref, 3>;
using M3 = std::array<V3, 3>;  // rows

// Constants of the geometry within this of 0 or +-1 are taken as exactly that: rotations by
// multiples of 90 degrees leave 1e-17 residues.
constexpr double kSnap = 1e-14;

double cleanValue(double x) {
  if (std::abs(x) < kSnap) return 0.0;
  if (std::abs(x - 1.0) < kSnap) return 1.0;
  if (std::abs(x + 1.0) < kSnap) return -1.0;
  return x;
}

struct Rigid {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  bool identity() const { return R.isIdentity(0.0) && t.isZero(0.0); }
};

Rigid rigid(const Eigen::Isometry3d& T) {
  Rigid r;
  r.R = T.linear().unaryExpr(&cleanValue);
  r.t = T.translation().unaryExpr(&cleanValue);
  return r;
}

struct JointStages {
  Rigid pre, post;
  JointType type = JointType::Revolute;
  Eigen::Vector3d u = Eigen::Vector3d::UnitZ();
  double offset = 0;  // revolute: the joint turns by q + offset
};

Eigen::Isometry3d rotAbout(const Eigen::Vector3d& u, double angle) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle, u).toRotationMatrix();
  return T;
}

// Where the part of a joint's constant translations along its axis goes: it commutes with the
// joint motion (a rotation about, or a translation along, that axis), so it can sit in `pre`
// or in `post`. Which side is cheaper depends on the zeros and the products shared there.
enum class AxisShift : std::uint8_t { Keep, ToPre, ToPost };

// The stages of every joint. A DH/MDH angle offset theta is moved out of the constant
// transforms into the joint angle, so that right-angle twists keep their exact zeros.
std::vector<JointStages> jointStages(const Model& model, const std::vector<AxisShift>& shift) {
  std::vector<JointStages> out;
  const int n = model.nq();
  const bool dh = model.convention == "dh" && static_cast<int>(model.dh.size()) == n;
  const bool mdh = model.convention == "mdh" && static_cast<int>(model.dh.size()) == n;
  for (int k = 0; k < n; ++k) {
    const Joint& j = model.joints[k];
    JointStages s;
    s.type = j.type;
    s.u = j.axis.unaryExpr(&cleanValue);
    Eigen::Isometry3d pre = j.pre, post = j.post;
    const double theta = (dh || mdh) ? model.dh[k].theta : 0.0;
    if (j.type == JointType::Revolute && theta != 0.0) {
      // Rot(u, q) commutes with Rot(u, theta): dh has it in front of post, mdh at the end of
      // pre (where it also commutes with the translation along the axis).
      if (dh) post = rotAbout(j.axis, -theta) * post;
      if (mdh) pre = pre * rotAbout(j.axis, -theta);
      s.offset = theta;
    }
    const AxisShift sh = shift[k];
    if (sh != AxisShift::Keep) {
      // pre = T(t_pre) R_pre; post = T(t_post) R_post; u is in the joint frame.
      const Eigen::Vector3d u = j.axis.normalized();
      const double along = sh == AxisShift::ToPre
                               ? u.dot(post.translation())
                               : u.dot(pre.linear().transpose() * pre.translation());
      if (cleanValue(along) != 0.0) {
        Eigen::Isometry3d move = Eigen::Isometry3d::Identity();
        move.translation() = along * u;
        if (sh == AxisShift::ToPre) {
          pre = pre * move;
          post.translation() -= along * u;
        } else {
          pre = pre * move.inverse();
          post = move * post;
        }
      }
    }
    s.pre = rigid(pre);
    s.post = rigid(post);
    out.push_back(s);
  }
  return out;
}

struct Motion {
  V3 w, dw, a;  // angular velocity, angular acceleration, linear acceleration of the origin
};

struct Wrench {
  V3 n, f;  // moment about the origin, force
};

class Builder {
 public:
  Builder(Graph& g, const Model& model, std::vector<JointStages> stages)
      : g_(g), model_(model), stages_(std::move(stages)) {
    zero_ = {Graph::zero(), Graph::zero(), Graph::zero()};
  }

  // Forward pass: fills the joint trigonometry and the motion of every link frame.
  void forward(const std::vector<Ref>& dq, const std::vector<Ref>& ddq, bool gravity) {
    const int n = model_.nq();
    q_.assign(n, Graph::zero());
    jointR_.assign(n, M3{});
    link_.assign(n, Motion{});
    dq_ = dq;
    ddq_ = ddq;
    Motion m{zero_, zero_, zero_};
    if (gravity)
      for (int i = 0; i < 3; ++i) m.a[i] = g_.constant(cleanValue(-model_.gravity[i]));
    for (int k = 0; k < n; ++k) {
      const JointStages& s = stages_[k];
      m = rigidForward(s.pre, m);
      const Ref qk = g_.input(InputKind::Q, k);
      const V3 u = constVec(s.u);
      if (s.type == JointType::Revolute) {
        const Ref angle = g_.add(qk, g_.constant(s.offset));
        const Ref c = g_.cos(angle), sn = g_.sin(angle);
        jointR_[k] = rodrigues(s.u, c, sn);
        const V3 wr = mulT(jointR_[k], m.w);
        const V3 wj = scale(u, dq[k]);
        m.w = addv(wr, wj);
        m.dw = addv(addv(mulT(jointR_[k], m.dw), scale(u, ddq[k])), cross(wr, wj));
        m.a = mulT(jointR_[k], m.a);
      } else {
        q_[k] = qk;
        const V3 d = scale(u, qk);
        // a' = a + U d + 2 w x (u dq) + u ddq
        V3 a = addv(m.a, uTimes(m, d));
        a = addv(a, scale(cross(m.w, scale(u, dq[k])), g_.constant(2.0)));
        m.a = addv(a, scale(u, ddq[k]));
      }
      m = rigidForward(s.post, m);
      link_[k] = m;
    }
  }

  // Backward pass for a classical parameter vector (layout of the model's ParameterSet).
  std::vector<Ref> torques(const std::vector<Ref>& pi, ParameterLayout layout, bool joint_terms) {
    const int n = model_.nq();
    std::vector<Ref> tau(n, Graph::zero());
    Wrench w{zero_, zero_};
    for (int k = n - 1; k >= 0; --k) {
      const JointStages& s = stages_[k];
      const Wrench own = linkWrench(link_[k], pi, k * layout.perLink());
      w.n = addv(w.n, own.n);
      w.f = addv(w.f, own.f);
      w = rigidBackward(s.post, w);
      const V3 u = constVec(s.u);
      Ref t;
      if (s.type == JointType::Revolute) {
        t = dot(u, w.n);
        w.n = mul(jointR_[k], w.n);
        w.f = mul(jointR_[k], w.f);
      } else {
        t = dot(u, w.f);
        w.n = addv(w.n, cross(scale(u, q_[k]), w.f));
      }
      if (joint_terms) {
        if (layout.rotor) t = g_.add(t, g_.mul(pi[layout.rotorIndex(k)], ddq_[k]));
        if (layout.friction) {
          t = g_.add(t, g_.mul(pi[layout.viscousIndex(k)], dq_[k]));
          t = g_.add(t, g_.mul(pi[layout.coulombIndex(k)], g_.sign(dq_[k])));
        }
      }
      tau[k] = t;
      if (k > 0) w = rigidBackward(s.pre, w);
    }
    return tau;
  }

 private:
  V3 constVec(const Eigen::Vector3d& v) {
    return {g_.constant(v[0]), g_.constant(v[1]), g_.constant(v[2])};
  }
  M3 constMat(const Eigen::Matrix3d& R) {
    M3 m;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m[i][j] = g_.constant(R(i, j));
    return m;
  }
  V3 addv(const V3& a, const V3& b) {
    return {g_.add(a[0], b[0]), g_.add(a[1], b[1]), g_.add(a[2], b[2])};
  }
  V3 scale(const V3& a, Ref s) { return {g_.mul(a[0], s), g_.mul(a[1], s), g_.mul(a[2], s)}; }
  Ref dot(const V3& a, const V3& b) {
    return g_.add(g_.add(g_.mul(a[0], b[0]), g_.mul(a[1], b[1])), g_.mul(a[2], b[2]));
  }
  V3 cross(const V3& a, const V3& b) {
    return {g_.sub(g_.mul(a[1], b[2]), g_.mul(a[2], b[1])),
            g_.sub(g_.mul(a[2], b[0]), g_.mul(a[0], b[2])),
            g_.sub(g_.mul(a[0], b[1]), g_.mul(a[1], b[0]))};
  }
  V3 mul(const M3& R, const V3& x) {
    V3 y;
    for (int i = 0; i < 3; ++i) y[i] = dot(R[i], x);
    return y;
  }
  V3 mulT(const M3& R, const V3& x) {
    V3 y;
    for (int i = 0; i < 3; ++i) y[i] = dot({R[0][i], R[1][i], R[2][i]}, x);
    return y;
  }
  // Rot(u, q) = (I + K^2) - cos q K^2 + sin q K, K = [u]x.
  M3 rodrigues(const Eigen::Vector3d& u, Ref c, Ref s) {
    Eigen::Matrix3d K;
    K << 0, -u.z(), u.y(), u.z(), 0, -u.x(), -u.y(), u.x(), 0;
    const Eigen::Matrix3d K2 = K * K;
    const Eigen::Matrix3d A0 = (Eigen::Matrix3d::Identity() + K2).unaryExpr(&cleanValue);
    const Eigen::Matrix3d A1 = (-K2).unaryExpr(&cleanValue);
    M3 R;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        R[i][j] = g_.add(g_.add(g_.constant(A0(i, j)), g_.mul(g_.constant(A1(i, j)), c)),
                         g_.mul(g_.constant(cleanValue(K(i, j))), s));
    return R;
  }
  // Entry (i, j) of U = [dw]x + [w]x^2: w_i w_j + [dw]x(i, j), diagonal -(w_j^2 + w_k^2).
  Ref uEntry(const Motion& m, int i, int j) {
    if (i == j) {
      const int a = (i + 1) % 3, b = (i + 2) % 3;
      return -g_.add(g_.mul(m.w[a], m.w[a]), g_.mul(m.w[b], m.w[b]));
    }
    const Ref ww = g_.mul(m.w[i], m.w[j]);
    // [dw]x(i, j) = -eps_ijk dw_k
    const int k = 3 - i - j;
    const bool plus = (j == (i + 2) % 3);  // (0,2), (1,0), (2,1): +dw_k
    return plus ? g_.add(ww, m.dw[k]) : g_.sub(ww, m.dw[k]);
  }
  V3 uTimes(const Motion& m, const V3& d) {
    V3 y;
    for (int i = 0; i < 3; ++i) {
      Ref s = Graph::zero();
      for (int j = 0; j < 3; ++j)
        if (d[j] != Graph::zero()) s = g_.add(s, g_.mul(uEntry(m, i, j), d[j]));
      y[i] = s;
    }
    return y;
  }
  Motion rigidForward(const Rigid& T, const Motion& m) {
    if (T.identity()) return m;
    const M3 R = constMat(T.R);
    Motion o;
    V3 a = m.a;
    if (!T.t.isZero(0.0)) a = addv(a, uTimes(m, constVec(T.t)));
    o.w = mulT(R, m.w);
    o.dw = mulT(R, m.dw);
    o.a = mulT(R, a);
    return o;
  }
  Wrench rigidBackward(const Rigid& T, const Wrench& w) {
    if (T.identity()) return w;
    const M3 R = constMat(T.R);
    Wrench o;
    o.f = mul(R, w.f);
    o.n = mul(R, w.n);
    if (!T.t.isZero(0.0)) o.n = addv(o.n, cross(constVec(T.t), o.f));
    return o;
  }

  // sum_k coef_k * param_k with equal coefficients (up to sign) gathered first.
  Ref linearForm(const std::vector<std::pair<Ref, Ref>>& terms) {
    std::vector<std::pair<Ref, Ref>> groups;
    for (const auto& [c, p] : terms) {
      if (c == Graph::zero() || p == Graph::zero()) continue;
      const Ref ca = c.abs(), ps = p.negatedIf(c.negative());
      bool found = false;
      for (auto& gr : groups)
        if (gr.first == ca) {
          gr.second = g_.add(gr.second, ps);
          found = true;
          break;
        }
      if (!found) groups.emplace_back(ca, ps);
    }
    Ref s = Graph::zero();
    for (const auto& [c, p] : groups) s = g_.add(s, g_.mul(c, p));
    return s;
  }

  // Wrench of one link about its origin, in its frame, linear in its ten parameters.
  Wrench linkWrench(const Motion& m, const std::vector<Ref>& pi, int c0) {
    std::array<std::vector<std::pair<Ref, Ref>>, 3> tn, tf;
    // Inertia: n += L(dw) I6 + w x (L(w) I6), L(v) I6 = I v.
    static const int rowOf[6][2] = {{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}};
    for (int p = 0; p < 6; ++p) {
      const Ref par = pi[c0 + p];
      if (par == Graph::zero()) continue;
      // column p of L(v): the tensor entry (r, c) contributes v_c to row r and v_r to row c.
      auto column = [&](const V3& v) {
        V3 col = zero_;
        const int r = rowOf[p][0], c = rowOf[p][1];
        col[r] = v[c];
        if (r != c) col[c] = v[r];
        return col;
      };
      const V3 coef = addv(column(m.dw), cross(m.w, column(m.w)));
      for (int i = 0; i < 3; ++i) tn[i].emplace_back(coef[i], par);
    }
    // First moments: n += MS x a, f += U MS.
    for (int j = 0; j < 3; ++j) {
      const Ref par = pi[c0 + 6 + j];
      if (par == Graph::zero()) continue;
      V3 e = zero_;
      e[j] = Graph::one();
      const V3 cn = cross(e, m.a);
      for (int i = 0; i < 3; ++i) {
        tn[i].emplace_back(cn[i], par);
        tf[i].emplace_back(uEntry(m, i, j), par);
      }
    }
    const Ref mass = pi[c0 + 9];
    if (mass != Graph::zero())
      for (int i = 0; i < 3; ++i) tf[i].emplace_back(m.a[i], mass);
    Wrench w;
    for (int i = 0; i < 3; ++i) {
      w.n[i] = linearForm(tn[i]);
      w.f[i] = linearForm(tf[i]);
    }
    return w;
  }

  Graph& g_;
  const Model& model_;
  std::vector<JointStages> stages_;
  V3 zero_;
  std::vector<Ref> q_, dq_, ddq_;
  std::vector<M3> jointR_;
  std::vector<Motion> link_;
};

}  // namespace

const char* toString(Function f) {
  switch (f) {
    case Function::InverseDynamics:
      return "inverse_dynamics";
    case Function::Gravity:
      return "gravity";
    case Function::Regressor:
      return "regressor";
  }
  return "?";
}

ParameterSet baseParameterSet(const Model& model, const BaseParameters& bp) {
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
  ParameterSet s;
  s.layout = layout;
  s.base = false;
  s.names = model.parameterNames(layout);
  const int P = layout.size(model.nq());
  s.E = Eigen::MatrixXd::Identity(P, P);
  s.values = model.parameters(layout);
  return s;
}

namespace {

GeneratedFunction generateWith(const Model& model, const ParameterSet& params, Function function,
                               bool numeric, const Eigen::VectorXd& values,
                               const std::vector<AxisShift>& shift) {
  const int n = model.nq(), np = params.size();
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

  GeneratedFunction out;
  out.function = function;
  out.n = n;
  out.np = np;
  out.numeric = numeric && function != Function::Regressor;
  Graph& g = out.graph;
  Builder b(g, model, jointStages(model, shift));

  std::vector<Ref> dq(n, Graph::zero()), ddq(n, Graph::zero());
  if (function != Function::Gravity)
    for (int k = 0; k < n; ++k) {
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
    out.outputs.assign(static_cast<size_t>(n) * np, Graph::zero());
    for (int col = 0; col < np; ++col) {
      const auto pi = classical([&](int c) { return g.constant(params.E(c, col)); });
      const auto tau = b.torques(pi, params.layout, true);
      for (int i = 0; i < n; ++i) out.outputs[static_cast<size_t>(i) * np + col] = tau[i];
    }
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
    out.outputs = b.torques(pi, params.layout, function == Function::InverseDynamics);
  }
  out.program = schedule(g, out.outputs);
  return out;
}

}  // namespace

GeneratedFunction generate(const Model& model, const ParameterSet& params, Function function,
                           bool numeric, const Eigen::VectorXd& values) {
  // Place each joint's along-axis translation where it costs least, one joint at a time.
  const int n = model.nq();
  std::vector<AxisShift> shift(n, AxisShift::Keep);
  GeneratedFunction best = generateWith(model, params, function, numeric, values, shift);
  auto cost = [](const GeneratedFunction& f) { return f.program.count.mul + f.program.count.add; };
  for (int k = 0; k < n; ++k)
    for (AxisShift sh : {AxisShift::ToPre, AxisShift::ToPost}) {
      std::vector<AxisShift> trial = shift;
      trial[k] = sh;
      GeneratedFunction f = generateWith(model, params, function, numeric, values, trial);
      if (cost(f) < cost(best)) {
        best = std::move(f);
        shift = std::move(trial);
      }
    }
  return best;
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
                           bool numeric, const Eigen::VectorXd& values) {
  checkIdentifier(name);
  if (functions.empty()) throw ModelError("codegen: no function to generate");
  GeneratedCode code;
  code.robot = model.name;
  code.name = name;
  code.n = model.nq();
  code.params = params;
  code.values = values.size() ? values : params.values;
  code.numeric = numeric;
  for (Function f : functions)
    code.functions.push_back(generate(model, params, f, numeric, values));
  return code;
}

}  // namespace mindyn::codegen
