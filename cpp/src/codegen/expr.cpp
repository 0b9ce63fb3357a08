#include "mindyn/codegen/expr.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "mindyn/spatial.hpp"

namespace mindyn::codegen {

namespace {

std::uint64_t mix(std::uint64_t h, std::uint64_t v) {
  h ^= v + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
  return h;
}

std::uint64_t hashNode(const Node& n) {
  std::uint64_t h = static_cast<std::uint64_t>(n.op);
  switch (n.op) {
    case Op::Const: {
      std::uint64_t bits;
      std::memcpy(&bits, &n.value, sizeof bits);
      return mix(h, bits);
    }
    case Op::Input:
      return mix(mix(h, static_cast<std::uint64_t>(n.kind)), static_cast<std::uint64_t>(n.index));
    default:
      return mix(mix(h, n.a.bits()), n.b.bits());
  }
}

bool sameNode(const Node& x, const Node& y) {
  if (x.op != y.op) return false;
  switch (x.op) {
    case Op::Const:
      return x.value == y.value;
    case Op::Input:
      return x.kind == y.kind && x.index == y.index;
    default:
      return x.a == y.a && x.b == y.b;
  }
}

}  // namespace

Graph::Graph() {
  Node z;
  z.value = 0.0;
  intern(z);
  Node o;
  o.value = 1.0;
  intern(o);
}

int Graph::intern(const Node& n) {
  const std::uint64_t h = hashNode(n);
  auto& bucket = table_[h];
  for (int id : bucket)
    if (sameNode(nodes_[id], n)) return id;
  nodes_.push_back(n);
  const int id = static_cast<int>(nodes_.size()) - 1;
  bucket.push_back(id);
  return id;
}

Ref Graph::constant(double v) {
  if (!std::isfinite(v)) throw std::invalid_argument("codegen: constant is not finite");
  if (v == 0.0) return zero();
  Node n;
  n.op = Op::Const;
  n.value = std::abs(v);
  return Ref(intern(n), v < 0.0);
}

double Graph::constantValue(Ref r) const {
  const double v = nodes_[r.id()].value;
  return r.negative() ? -v : v;
}

Ref Graph::input(InputKind kind, int index) {
  Node n;
  n.op = Op::Input;
  n.kind = kind;
  n.index = index;
  return Ref(intern(n), false);
}

Ref Graph::sin(Ref x) {
  if (isConstant(x)) return constant(std::sin(constantValue(x)));
  Node n;
  n.op = Op::Sin;
  n.a = x.abs();
  return Ref(intern(n), x.negative());  // sin(-x) = -sin(x)
}

Ref Graph::cos(Ref x) {
  if (isConstant(x)) return constant(std::cos(constantValue(x)));
  Node n;
  n.op = Op::Cos;
  n.a = x.abs();
  return Ref(intern(n), false);  // cos(-x) = cos(x)
}

Ref Graph::sign(Ref x) {
  if (isConstant(x)) return constant(sgn(constantValue(x)));
  Node n;
  n.op = Op::Sign;
  n.a = x.abs();
  return Ref(intern(n), x.negative());
}

Ref Graph::tanh(Ref x) {
  if (isConstant(x)) return constant(std::tanh(constantValue(x)));
  Node n;
  n.op = Op::Tanh;
  n.a = x.abs();
  return Ref(intern(n), x.negative());  // tanh(-x) = -tanh(x)
}

Ref Graph::exp(Ref x) {
  if (isConstant(x)) return constant(std::exp(constantValue(x)));
  Node n;
  n.op = Op::Exp;
  n.a = x;
  return Ref(intern(n), false);
}

Ref Graph::add(Ref a, Ref b) {
  if (a.id() == 0) return b;
  if (b.id() == 0) return a;
  if (isConstant(a) && isConstant(b)) return constant(constantValue(a) + constantValue(b));
  if (a.abs() == b.abs() && a != b) return zero();
  if (a == b) return mul(constant(2.0), a);  // x + x = 2 x, which gathers with other constants
  // Cancellation one level down: x + (-x + y) = y.
  for (int side = 0; side < 2; ++side) {
    const Ref s = side ? a : b, t = side ? b : a;
    const Node& ns = nodes_[s.id()];
    if (ns.op != Op::Add) continue;
    const Ref s1 = ns.a.negatedIf(s.negative()), s2 = ns.b.negatedIf(s.negative());
    if (s1 == -t) return s2;
    if (s2 == -t) return s1;
  }
  if (a.id() > b.id()) std::swap(a, b);
  const bool s = a.negative();
  Node n;
  n.op = Op::Add;
  n.a = a.abs();
  n.b = b.negatedIf(s);
  return Ref(intern(n), s);
}

Ref Graph::mul(Ref a, Ref b) {
  const bool s = a.negative() != b.negative();
  a = a.abs();
  b = b.abs();
  if (a.id() == 0 || b.id() == 0) return zero();
  if (a.id() == 1) return b.negatedIf(s);
  if (b.id() == 1) return a.negatedIf(s);
  const bool ca = isConstant(a), cb = isConstant(b);
  if (ca && cb) return constant(nodes_[a.id()].value * nodes_[b.id()].value).negatedIf(s);
  // Constants gather: c1 * (c2 * x) = (c1 c2) * x.
  if (ca || cb) {
    const Ref c = ca ? a : b, x = ca ? b : a;
    const Node& nx = nodes_[x.id()];
    if (nx.op == Op::Mul && (isConstant(nx.a) || isConstant(nx.b))) {
      const Ref c2 = isConstant(nx.a) ? nx.a : nx.b, y = isConstant(nx.a) ? nx.b : nx.a;
      return mul(constant(nodes_[c.id()].value * nodes_[c2.id()].value), y).negatedIf(s);
    }
  }
  if (a.id() > b.id()) std::swap(a, b);
  Node n;
  n.op = Op::Mul;
  n.a = a;
  n.b = b;
  return Ref(intern(n), s);
}

Ref Graph::sum(const std::vector<Ref>& terms) {
  Ref s = zero();
  for (Ref t : terms) s = add(s, t);
  return s;
}

std::vector<double> Graph::evaluate(const InputValues& in) const {
  std::vector<double> v(nodes_.size());
  auto val = [&v](Ref r) { return r.negative() ? -v[r.id()] : v[r.id()]; };
  for (size_t i = 0; i < nodes_.size(); ++i) {
    const Node& n = nodes_[i];
    switch (n.op) {
      case Op::Const:
        v[i] = n.value;
        break;
      case Op::Input: {
        const double* src = n.kind == InputKind::Q      ? in.q
                            : n.kind == InputKind::DQ   ? in.dq
                            : n.kind == InputKind::DDQ  ? in.ddq
                            : n.kind == InputKind::DQR  ? in.dqr
                            : n.kind == InputKind::DDQR ? in.ddqr
                            : n.kind == InputKind::S    ? in.s
                            : n.kind == InputKind::F    ? in.f
                                                        : in.p;
        if (!src) throw std::invalid_argument("codegen: evaluate() is missing an input array");
        v[i] = src[n.index];
        break;
      }
      case Op::Sin:
        v[i] = std::sin(val(n.a));
        break;
      case Op::Cos:
        v[i] = std::cos(val(n.a));
        break;
      case Op::Sign:
        v[i] = sgn(val(n.a));
        break;
      case Op::Tanh:
        v[i] = std::tanh(val(n.a));
        break;
      case Op::Exp:
        v[i] = std::exp(val(n.a));
        break;
      case Op::Add:
        v[i] = val(n.a) + val(n.b);
        break;
      case Op::Mul:
        v[i] = val(n.a) * val(n.b);
        break;
    }
  }
  return v;
}

Program schedule(const Graph& graph, const std::vector<Ref>& outputs) {
  Program prog;
  prog.outputs = outputs;
  prog.uses.assign(graph.size(), 0);
  std::vector<char> seen(graph.size(), 0);
  std::vector<int> stack;
  for (Ref r : outputs) {
    prog.uses[r.id()]++;
    stack.push_back(r.id());
  }
  while (!stack.empty()) {
    const int id = stack.back();
    stack.pop_back();
    if (seen[id]) continue;
    seen[id] = 1;
    const Node& n = graph.node(id);
    if (n.op == Op::Const || n.op == Op::Input) continue;
    prog.uses[n.a.id()]++;
    stack.push_back(n.a.id());
    if (n.op == Op::Add || n.op == Op::Mul) {
      prog.uses[n.b.id()]++;
      stack.push_back(n.b.id());
    }
  }
  for (int id = 0; id < graph.size(); ++id) {
    if (!seen[id]) continue;
    switch (graph.node(id).op) {
      case Op::Const:
      case Op::Input:
        continue;
      case Op::Sin:
      case Op::Cos:
        prog.count.trig++;
        break;
      case Op::Sign:
        prog.count.sign++;
        break;
      case Op::Tanh:
        prog.count.tanh++;
        break;
      case Op::Exp:
        prog.count.exp++;
        break;
      case Op::Add:
        prog.count.add++;
        break;
      case Op::Mul:
        prog.count.mul++;
        break;
    }
    prog.order.push_back(id);
  }
  for (Ref r : outputs)
    if (r.negative() && !graph.isConstant(r)) prog.count.neg++;
  return prog;
}

}  // namespace mindyn::codegen
