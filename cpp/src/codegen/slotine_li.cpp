// The Slotine-Li products of an adaptive controller step (generateSlotineLi): the Slotine-Li
// recursion of mindyn/slotine_li.hpp written into an expression graph on the stages of every
// joint (stages.hpp), in spatial motion and force vectors of each link frame; Y p by the columns
// of Y or by one force pass, Y^T s by the columns or by the reverse (adjoint) pass of s^T Y p.
#include <string>
#include <utility>
#include <vector>

#include "builder.hpp"
#include "internal.hpp"
#include "mindyn/codegen/newton_euler.hpp"

namespace mindyn::codegen {

namespace {

using internal::AxisShift;
using internal::Builder;
using internal::jointStages;
using internal::JointStages;
using internal::M3;
using internal::P10;
using internal::Rigid;
using internal::V3;

// The Slotine-Li recursion (mindyn/slotine_li.hpp) on the same stages: spatial motion vectors
// (angular, linear velocity of the origin) of the actual velocity v, the reference velocity v_r
// and acceleration a_r, in each link frame; the wrench of link k about its origin is
// f = I (a_r - 1/2 v x v_r) + 1/2 (v x* I v_r + v_r x* I v).
class SlotineLiBuilder : public Builder {
 public:
  using Builder::Builder;

  void forward(const std::vector<Ref>& dq, const std::vector<Ref>& dqr,
               const std::vector<Ref>& ddqr) {
    Graph& g = graph();
    const int n = model_.nq();
    dq_ = dq;
    dqr_ = dqr;
    ddqr_ = ddqr;
    v_.assign(n, SV{});
    vr_.assign(n, SV{});
    ar_.assign(n, SV{});
    R_.assign(n, M3{});
    d_.assign(n, V3{});
    SV base{zero_, zero_}, baseA{zero_, zero_};
    for (int i = 0; i < 3; ++i) baseA.l[i] = g.constant(-gravity_[i]);
    for (int k = 0; k < n; ++k) {
      const JointStages& s = stages_[k];
      const int parent = model_.parent(k);
      SV v = toChild(s.pre, parent < 0 ? base : v_[parent]);
      SV vr = toChild(s.pre, parent < 0 ? base : vr_[parent]);
      SV ar = toChild(s.pre, parent < 0 ? baseA : ar_[parent]);
      const V3 u = constVec(s.u);
      if (s.type == JointType::Revolute) {
        const Ref angle = g.add(g.input(InputKind::Q, k), g.constant(s.offset));
        R_[k] = rodrigues(s.u, g.cos(angle), g.sin(angle));
        for (SV* x : {&v, &vr, &ar}) *x = {mulT(R_[k], x->w), mulT(R_[k], x->l)};
        const V3 sr = scale(u, dqr[k]);
        ar.w = addv(addv(ar.w, scale(u, ddqr[k])), cross(v.w, sr));
        ar.l = addv(ar.l, cross(v.l, sr));
        v.w = addv(v.w, scale(u, dq[k]));
        vr.w = addv(vr.w, sr);
      } else {
        d_[k] = scale(u, g.input(InputKind::Q, k));
        for (SV* x : {&v, &vr, &ar}) x->l = addv(x->l, cross(x->w, d_[k]));
        const V3 sr = scale(u, dqr[k]);
        ar.l = addv(addv(ar.l, scale(u, ddqr[k])), cross(v.w, sr));
        v.l = addv(v.l, scale(u, dq[k]));
        vr.l = addv(vr.l, sr);
      }
      v = toChild(s.post, v);
      vr = toChild(s.post, vr);
      ar = toChild(s.post, ar);
      v_[k] = v;
      vr_[k] = vr;
      ar_[k] = ar;
    }
  }

  // tau = Y(q, dq, dqr, ddqr) pi for classical parameters pi (layout `layout`). Each link's
  // total wrench (its own and its descendants') is carried into its parent's frame and added to
  // the parent's.
  std::vector<Ref> torques(const std::vector<Ref>& pi, ParameterLayout layout) {
    Graph& g = graph();
    const int n = model_.nq();
    std::vector<Ref> tau(n, Graph::zero());
    // the children's wrenches in each link's frame: w = moment about the origin, l = force
    std::vector<SV> children(n, SV{zero_, zero_});
    for (int k = n - 1; k >= 0; --k) {
      const JointStages& s = stages_[k];
      SV f = children[k];
      P10 p;
      for (int i = 0; i < 10; ++i) p[i] = pi[k * layout.perLink() + i];
      const SV& v = v_[k];
      const SV& vr = vr_[k];
      const SV half = {scale(crossMotion(v, vr).w, g.constant(0.5)),
                       scale(crossMotion(v, vr).l, g.constant(0.5))};
      const SV own = inertia(p, {subv(ar_[k].w, half.w), subv(ar_[k].l, half.l)});
      const SV gyro = addsv(crossForce(v, inertia(p, vr)), crossForce(vr, inertia(p, v)));
      f = addsv(f, addsv(own, {scale(gyro.w, g.constant(0.5)), scale(gyro.l, g.constant(0.5))}));
      f = toParent(s.post, f);
      const V3 u = constVec(s.u);
      Ref t = dot(u, s.type == JointType::Revolute ? f.w : f.l);
      tau[k] = t;
      const int parent = model_.parent(k);
      if (parent < 0) continue;
      if (s.type == JointType::Revolute)
        f = {mul(R_[k], f.w), mul(R_[k], f.l)};
      else
        f.w = addv(f.w, cross(d_[k], f.l));
      children[parent] = addsv(children[parent], toParent(s.pre, f));
    }
    // rotor inertia through the reference acceleration, friction through the actual velocity
    internal::addDriveTerms(g, model_, pi, layout, ddqr_, tau, dq_, tau);
    return tau;
  }

 private:
  SV crossMotion(const SV& a, const SV& b) {
    return {cross(a.w, b.w), addv(cross(a.w, b.l), cross(a.l, b.w))};
  }
  SV crossForce(const SV& a, const SV& x) {
    return {addv(cross(a.w, x.w), cross(a.l, x.l)), cross(a.w, x.l)};
  }

  std::vector<Ref> dqr_, ddqr_;
  std::vector<SV> v_, vr_, ar_;
  std::vector<M3> R_;
  std::vector<V3> d_;  // prismatic joints: the joint displacement u q
};

// d(sum_k w_k out_k)/d p for outputs linear in the parameter inputs (reverse pass over the
// graph, adding the adjoint nodes to it): the gradient per parameter index (size np).
std::vector<Ref> adjoint(Graph& g, const std::vector<Ref>& out, const std::vector<Ref>& w, int np) {
  const int size = g.size();
  std::vector<char> dep(size, 0);
  for (int id = 0; id < size; ++id) {
    const Node& n = g.node(id);
    if (n.op == Op::Input) dep[id] = n.kind == InputKind::P;
    if (n.op == Op::Add || n.op == Op::Mul) dep[id] = dep[n.a.id()] || dep[n.b.id()];
    if (n.op == Op::Sin || n.op == Op::Cos || n.op == Op::Sign || n.op == Op::Tanh ||
        n.op == Op::Exp)
      dep[id] = dep[n.a.id()];
  }
  std::vector<Ref> adj(size, Graph::zero()), grad(np, Graph::zero());
  for (size_t k = 0; k < out.size(); ++k)
    adj[out[k].id()] = g.add(adj[out[k].id()], w[k].negatedIf(out[k].negative()));
  for (int id = size - 1; id >= 0; --id) {
    if (!dep[id] || adj[id] == Graph::zero()) continue;
    const Node n = g.node(id);  // a copy: adding nodes may move the graph's storage
    const Ref a = adj[id];
    if (n.op == Op::Input) {
      grad[n.index] = g.add(grad[n.index], a);
    } else if (n.op == Op::Add) {
      adj[n.a.id()] = g.add(adj[n.a.id()], a.negatedIf(n.a.negative()));
      adj[n.b.id()] = g.add(adj[n.b.id()], a.negatedIf(n.b.negative()));
    } else if (n.op == Op::Mul) {
      if (dep[n.a.id()]) adj[n.a.id()] = g.add(adj[n.a.id()], g.mul(a, n.b));
      if (dep[n.b.id()]) adj[n.b.id()] = g.add(adj[n.b.id()], g.mul(a, n.a));
    } else {
      throw ModelError("codegen: the Slotine-Li torque is not linear in the parameters");
    }
  }
  return grad;
}

GeneratedFunction slotineLiWith(const Model& model, const ParameterSet& params, bool normalised,
                                bool pass, bool adjointPass) {
  const int n = model.nq(), np = params.size(), P = params.layout.size(n);
  const int off0 = np - params.offsets;
  internal::checkDriveTerms(model, params.layout);
  GeneratedFunction out;
  out.function = Function::SlotineLi;
  out.n = n;
  out.np = np;
  Graph& g = out.graph;
  SlotineLiBuilder b(g, model, jointStages(model, std::vector<AxisShift>(n, AxisShift::Keep)));
  std::vector<Ref> dq(n), dqr(n), ddqr(n), s(n);
  for (int k = 0; k < n; ++k) {
    dq[k] = g.input(InputKind::DQ, k);
    dqr[k] = g.input(InputKind::DQR, k);
    ddqr[k] = g.input(InputKind::DDQR, k);
    s[k] = g.input(InputKind::S, k);
  }
  b.forward(dq, dqr, ddqr);
  std::vector<Ref> p(np);
  for (int j = 0; j < np; ++j) p[j] = g.input(InputKind::P, j);
  // the regressor's columns, when a product needs them
  std::vector<std::vector<Ref>> Y(np);
  if (!pass || !adjointPass || normalised) {
    for (int col = 0; col < off0; ++col) {
      std::vector<Ref> pi(P);
      for (int c = 0; c < P; ++c) pi[c] = g.constant(params.E(c, col));
      Y[col] = b.torques(pi, params.layout);
    }
    for (int k = 0; k < params.offsets; ++k) {
      Y[off0 + k].assign(n, Graph::zero());
      Y[off0 + k][k] = Graph::one();
    }
  }
  std::vector<Ref> yp(n, Graph::zero());
  if (pass) {
    std::vector<Ref> pi(P, Graph::zero());
    for (int c = 0; c < P; ++c)
      for (int j = 0; j < off0; ++j)
        if (params.E(c, j) != 0.0) pi[c] = g.add(pi[c], g.mul(g.constant(params.E(c, j)), p[j]));
    yp = b.torques(pi, params.layout);
    for (int k = 0; k < params.offsets; ++k) yp[k] = g.add(yp[k], p[off0 + k]);
  } else {
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < np; ++j) yp[i] = g.add(yp[i], g.mul(Y[j][i], p[j]));
  }
  std::vector<Ref> yts(np, Graph::zero());
  if (adjointPass) {
    yts = adjoint(g, yp, s, np);
  } else {
    for (int j = 0; j < np; ++j)
      for (int i = 0; i < n; ++i) yts[j] = g.add(yts[j], g.mul(Y[j][i], s[i]));
  }
  out.outputs = yp;
  out.outputs.insert(out.outputs.end(), yts.begin(), yts.end());
  if (normalised) {
    Ref yy = Graph::zero();
    for (int j = 0; j < np; ++j)
      for (int i = 0; i < n; ++i) yy = g.add(yy, g.mul(Y[j][i], Y[j][i]));
    out.outputs.push_back(yy);
  }
  out.program = schedule(g, out.outputs);
  return out;
}

}  // namespace

const char* toString(SlotineLiForm f) {
  switch (f) {
    case SlotineLiForm::Columns:
      return "Y from its columns";
    case SlotineLiForm::PassColumns:
      return "Y p by a force pass, Y^T s from the columns";
    case SlotineLiForm::ColumnsAdjoint:
      return "Y p from the columns, Y^T s by the adjoint pass";
    case SlotineLiForm::PassAdjoint:
      return "Y p by a force pass, Y^T s by its adjoint pass";
  }
  return "?";
}

GeneratedFunction internal::generateSlotineLiForm(const Model& model, const ParameterSet& params,
                                                  bool normalised, SlotineLiForm form) {
  const bool pass = form == SlotineLiForm::PassColumns || form == SlotineLiForm::PassAdjoint;
  const bool adj = form == SlotineLiForm::ColumnsAdjoint || form == SlotineLiForm::PassAdjoint;
  return slotineLiWith(model, params, normalised, pass, adj);
}

GeneratedFunction generateSlotineLi(const Model& model, const ParameterSet& params, bool normalised,
                                    std::vector<SlotineLiVariant>* variants) {
  requireSingleDof(model, "the generated Slotine-Li products");
  const int n = model.nq();
  if (params.E.rows() != params.layout.size(n) || params.E.cols() != params.size())
    throw ModelError("codegen: the parameter map does not fit the model");
  if (params.offsets != 0 && params.offsets != n)
    throw ModelError("codegen: " + std::to_string(params.offsets) + " torque offsets for " +
                     std::to_string(n) + " joints");
  GeneratedFunction best;
  bool have = false;
  for (SlotineLiForm form : {SlotineLiForm::Columns, SlotineLiForm::PassColumns,
                             SlotineLiForm::ColumnsAdjoint, SlotineLiForm::PassAdjoint}) {
    GeneratedFunction f = internal::generateSlotineLiForm(model, params, normalised, form);
    if (variants) variants->push_back({form, f.program.count});
    const OpCount& c = f.program.count;
    const OpCount& d = best.program.count;
    if (!have || c.mul + c.add < d.mul + d.add ||
        (c.mul + c.add == d.mul + d.add && c.mul < d.mul)) {
      best = std::move(f);
      have = true;
    }
  }
  jointStages(model, std::vector<AxisShift>(n, AxisShift::Keep), &best.snap);
  internal::cleanGeometry<3, 1>(model.gravity, false, &best.snap);
  return best;
}

}  // namespace mindyn::codegen
