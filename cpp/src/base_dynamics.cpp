#include "mindyn/base_dynamics.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "mindyn/sincos.hpp"

namespace mindyn {

using codegen::Function;
using codegen::GeneratedFunction;
using codegen::InputKind;
using codegen::Node;
using codegen::Op;
using codegen::Ref;

Tape::Tape(const GeneratedFunction& f) : count_(f.program.count) {
  const codegen::Graph& g = f.graph;
  const int N = g.size();
  const auto& uses = f.program.uses;
  auto isMul = [&g](Ref r) { return g.node(r.id()).op == Op::Mul; };
  auto computed = [&g](int id) {
    const Op o = g.node(id).op;
    return o != Op::Const && o != Op::Input;
  };
  // Products read by a single sum are fused into it.
  std::vector<char> fused(N, 0);
  for (int id : f.program.order) {
    const Node& n = g.node(id);
    if (n.op != Op::Add) continue;
    if (isMul(n.a) && uses[n.a.id()] == 1)
      fused[n.a.id()] = 1;
    else if (isMul(n.b) && uses[n.b.id()] == 1)
      fused[n.b.id()] = 1;
  }
  // The sine and the cosine of one angle come from one instruction, the sine's when both are
  // used: owner[id] is the instruction node that computes id.
  std::vector<int> owner(N), partner(N, -1);
  for (int id = 0; id < N; ++id) owner[id] = id;
  {
    std::unordered_map<std::uint32_t, int> sinOf;
    for (int id : f.program.order)
      if (g.node(id).op == Op::Sin) sinOf[g.node(id).a.bits()] = id;
    for (int id : f.program.order)
      if (g.node(id).op == Op::Cos) {
        const auto it = sinOf.find(g.node(id).a.bits());
        if (it == sinOf.end()) continue;
        owner[id] = it->second;
        partner[it->second] = id;
      }
  }
  // Slots: constants (with 0) and inputs first, then the computed values, then the cosines
  // computed with their sines, then one slot for an unused result.
  std::vector<std::uint32_t> slot(N, 0);
  for (int id = 0; id < N; ++id) {
    const Node& n = g.node(id);
    if ((id != 0 && uses[id] == 0) || computed(id)) continue;
    slot[id] = static_cast<std::uint32_t>(slots_.size());
    slots_.push_back(n.op == Op::Const ? n.value : 0.0);
    if (n.op == Op::Input)
      loads_.push_back({slot[id], n.kind, static_cast<std::uint32_t>(n.index)});
  }
  first_ = static_cast<std::uint32_t>(slots_.size());

  auto kindOf = [&](int id) {
    const Node& n = g.node(id);
    switch (n.op) {
      case Op::Sin:
      case Op::Cos:
        return SinCos;
      case Op::Sign:
        return Sign;
      case Op::Tanh:
        return Tanh;
      case Op::Exp:
        return Exp;
      case Op::Mul:
        return Mul;
      default:
        break;
    }
    // a + b with a positive; at most one of them a fused product x * y (positive factors)
    if (fused[n.a.id()]) return n.b.negative() ? MulSub : MulAdd;
    if (fused[n.b.id()]) return n.b.negative() ? SubMul : MulAdd;
    return n.b.negative() ? Sub : Add;
  };
  std::vector<int> nodes;  // one per instruction
  for (int id : f.program.order)
    if (!fused[id] && owner[id] == id) nodes.push_back(id);
  // The instructions an instruction reads (through a fused product too).
  auto reads = [&](int id) {
    std::vector<int> r;
    const Node& n = g.node(id);
    std::vector<Ref> ops{n.a};
    if (n.op == Op::Add || n.op == Op::Mul) ops.push_back(n.b);
    for (size_t i = 0; i < ops.size(); ++i) {
      const Ref x = ops[i];
      if (fused[x.id()]) {
        ops.push_back(g.node(x.id()).a);
        ops.push_back(g.node(x.id()).b);
        continue;
      }
      if (computed(x.id())) r.push_back(owner[x.id()]);
    }
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
    return r;
  };
  // List scheduling: keep taking ready instructions of the current kind, so that runs are long.
  std::vector<int> pending(N, 0);
  std::vector<std::vector<int>> readers(N);
  for (int id : nodes)
    for (int d : reads(id)) {
      pending[id]++;
      readers[d].push_back(id);
    }
  std::vector<std::vector<int>> ready(kKinds);
  for (int id : nodes)
    if (pending[id] == 0) ready[kindOf(id)].push_back(id);
  // How many instructions a run of kind k would take from here (what it makes ready included).
  auto runLength = [&](int k) {
    std::vector<int> left = pending, todo = ready[k];
    size_t len = 0;
    while (!todo.empty()) {
      const int id = todo.back();
      todo.pop_back();
      ++len;
      for (int r : readers[id])
        if (--left[r] == 0 && kindOf(r) == k) todo.push_back(r);
    }
    return len;
  };
  std::vector<int> order;
  order.reserve(nodes.size());
  int kind = -1;
  while (order.size() < nodes.size()) {
    if (kind < 0 || ready[kind].empty()) {
      // the kind whose run, taken to the end, is the longest
      size_t longest = 0;
      for (int k = 0; k < kKinds; ++k) {
        if (ready[k].empty()) continue;
        const size_t len = runLength(k);
        if (len > longest) {
          longest = len;
          kind = k;
        }
      }
      runs_.push_back({static_cast<Kind>(kind), static_cast<std::uint32_t>(order.size()), 0});
    }
    std::vector<int> batch;
    std::swap(batch, ready[kind]);
    for (int id : batch) {
      slot[id] = first_ + static_cast<std::uint32_t>(order.size());
      order.push_back(id);
    }
    for (int id : batch)
      for (int r : readers[id])
        if (--pending[r] == 0) ready[kindOf(r)].push_back(r);
  }
  for (size_t i = 0; i < runs_.size(); ++i)
    runs_[i].end =
        i + 1 < runs_.size() ? runs_[i + 1].begin : static_cast<std::uint32_t>(order.size());
  std::uint32_t next = first_ + static_cast<std::uint32_t>(order.size());
  for (int id : order)
    if (partner[id] >= 0) slot[partner[id]] = next++;
  const std::uint32_t unused = next++;
  slots_.resize(next, 0.0);
  code_.reserve(order.size());
  for (int id : order) {
    const Node& n = g.node(id);
    Instruction in{slot[n.a.id()], slot[n.b.id()], 0};
    switch (kindOf(id)) {
      case SinCos: {
        const bool isSin = n.op == Op::Sin;
        const std::uint32_t other = partner[id] >= 0 ? slot[partner[id]] : unused;
        in.b = isSin ? slot[id] : other;
        in.c = isSin ? other : slot[id];
        break;
      }
      case Mul:
      case Sign:
      case Tanh:
        break;
      case Exp:
        in.b = n.a.negative() ? 1 : 0;
        break;
      case Add:
      case Sub:
        in = {slot[n.a.id()], 0, slot[n.b.id()]};
        break;
      default: {  // a fused product and a sum
        const Ref prod = fused[n.a.id()] ? n.a : n.b, other = fused[n.a.id()] ? n.b : n.a;
        const Node& m = g.node(prod.id());
        in = {slot[m.a.id()], slot[m.b.id()], slot[other.id()]};
        break;
      }
    }
    code_.push_back(in);
  }
  for (Ref r : f.outputs) outputs_.emplace_back(slot[r.id()], r.negative());
}

void Tape::run(const double* q, const double* dq, const double* ddq, const double* p,
               double* out) noexcept {
  double* v = slots_.data();
  for (const Load& l : loads_) {
    const double* src = l.kind == InputKind::Q     ? q
                        : l.kind == InputKind::DQ  ? dq
                        : l.kind == InputKind::DDQ ? ddq
                                                   : p;
    v[l.slot] = src[l.index];
  }
  const Instruction* c = code_.data();
  double* dst = v + first_;
  for (const Run& r : runs_) {
    const std::uint32_t b = r.begin, e = r.end;
    switch (r.kind) {
      case Mul:
        for (std::uint32_t i = b; i < e; ++i) dst[i] = v[c[i].a] * v[c[i].b];
        break;
      case Add:
        for (std::uint32_t i = b; i < e; ++i) dst[i] = v[c[i].a] + v[c[i].c];
        break;
      case Sub:
        for (std::uint32_t i = b; i < e; ++i) dst[i] = v[c[i].a] - v[c[i].c];
        break;
      case MulAdd:
        for (std::uint32_t i = b; i < e; ++i) dst[i] = v[c[i].a] * v[c[i].b] + v[c[i].c];
        break;
      case MulSub:
        for (std::uint32_t i = b; i < e; ++i) dst[i] = v[c[i].a] * v[c[i].b] - v[c[i].c];
        break;
      case SubMul:
        for (std::uint32_t i = b; i < e; ++i) dst[i] = v[c[i].c] - v[c[i].a] * v[c[i].b];
        break;
      case SinCos:
        for (std::uint32_t i = b; i < e; ++i) sinCos(v[c[i].a], v[c[i].b], v[c[i].c]);
        break;
      case Sign:
        for (std::uint32_t i = b; i < e; ++i) {
          const double x = v[c[i].a];
          dst[i] = x > 0.0 ? 1.0 : (x < 0.0 ? -1.0 : 0.0);
        }
        break;
      case Tanh:
        for (std::uint32_t i = b; i < e; ++i) dst[i] = std::tanh(v[c[i].a]);
        break;
      case Exp:
        for (std::uint32_t i = b; i < e; ++i) dst[i] = std::exp(c[i].b ? -v[c[i].a] : v[c[i].a]);
        break;
    }
  }
  for (size_t i = 0; i < outputs_.size(); ++i)
    out[i] = outputs_[i].second ? -v[outputs_[i].first] : v[outputs_[i].first];
}

namespace {
const BaseParameters& checked(const Model& model, const BaseParameters& base) {
  if (base.eom.decision.Y.cols() != base.layout.size(model.nq()))
    throw ModelError("base parameters computed for another model (" +
                     std::to_string(base.eom.decision.Y.cols()) + " classical parameters, " +
                     std::to_string(base.layout.size(model.nq())) + " expected)");
  return base;
}
}  // namespace

BaseDynamics::BaseDynamics(const Model& model, const BaseParameters& base)
    : BaseDynamics(model, codegen::baseParameterSet(model, checked(model, base))) {}

BaseDynamics::BaseDynamics(const Model& model, const codegen::ParameterSet& ps)
    : n_(model.nq()), np_(ps.size()), layout_(ps.layout), names_(ps.names) {
  requireSingleDof(model, "the runtime base-parameter dynamics");
  for (Function f : {Function::InverseDynamics, Function::Gravity, Function::Regressor}) {
    const GeneratedFunction g = codegen::generate(model, ps, f);
    (f == Function::InverseDynamics ? id_
     : f == Function::Gravity       ? gravity_
                                    : regressor_) = Tape(g);
    snap_.include(g.snap);
  }
  qb_.resize(n_);
  dqb_.resize(n_);
  ddqb_.resize(n_);
  pb_.resize(np_);
  out_.resize(static_cast<long>(n_) * np_);
}

void BaseDynamics::inverseDynamics(const VecRef& q, const VecRef& dq, const VecRef& ddq,
                                   const VecRef& pb, VecOut tau) noexcept {
  qb_ = q;
  dqb_ = dq;
  ddqb_ = ddq;
  pb_ = pb;
  id_.run(qb_.data(), dqb_.data(), ddqb_.data(), pb_.data(), out_.data());
  tau = out_.head(n_);
}

void BaseDynamics::gravity(const VecRef& q, const VecRef& pb, VecOut tau) noexcept {
  qb_ = q;
  pb_ = pb;
  gravity_.run(qb_.data(), nullptr, nullptr, pb_.data(), out_.data());
  tau = out_.head(n_);
}

void BaseDynamics::regressor(const VecRef& q, const VecRef& dq, const VecRef& ddq,
                             MatOut Wb) noexcept {
  qb_ = q;
  dqb_ = dq;
  ddqb_ = ddq;
  regressor_.run(qb_.data(), dqb_.data(), ddqb_.data(), nullptr, out_.data());
  for (int i = 0; i < n_; ++i)
    for (int b = 0; b < np_; ++b) Wb(i, b) = out_[static_cast<long>(i) * np_ + b];
}

const codegen::OpCount& BaseDynamics::count(Function f) const {
  return f == Function::InverseDynamics ? id_.count()
         : f == Function::Gravity       ? gravity_.count()
                                        : regressor_.count();
}

}  // namespace mindyn
