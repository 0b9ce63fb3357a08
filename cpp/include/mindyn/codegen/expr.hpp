// Expression graph for generated code: scalar nodes over the inputs q (through sin/cos), dq, ddq
// and the parameters, built with constant folding, removal of multiplications by 0 and +-1 and
// additions of 0, and common-subexpression elimination by hash-consing. Signs live on the edges
// (a Ref is a node with a sign), so x*y, (-x)*y and -(x*y) are one node, and a - b and b - a are
// one node used with opposite signs: negation costs nothing until it reaches an output. A sum
// that cancels one of the terms of an operand, x + (-x + y), is that remaining term.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

namespace mindyn::codegen {

enum class Op : std::uint8_t {
  Const,  // value >= 0 (the sign is on the Ref)
  Input,  // q, dq, ddq or a parameter
  Sin,
  Cos,
  Sign,  // sign(x) in {-1, 0, 1}
  Add,   // a + b; a is positive, b carries its sign
  Mul,   // a * b; both positive, a.id <= b.id
  Tanh,  // tanh(a) (smooth Coulomb friction)
  Exp,   // exp(a) (Stribeck friction); a keeps its sign
};

// DQR, DDQR, S: the reference velocity and acceleration and the sliding variable of the
// Slotine-Li controller step (local arrays of the generated step function). F: the contact
// wrenches of a floating-base inverse dynamics (6 per contact link).
enum class InputKind : std::uint8_t { Q, DQ, DDQ, P, DQR, DDQR, S, F };

/// The argument name of an input kind in generated code: q, dq, ddq, p, dqr, ddqr, s, f.
inline const char* inputName(InputKind k) {
  switch (k) {
    case InputKind::Q:
      return "q";
    case InputKind::DQ:
      return "dq";
    case InputKind::DDQ:
      return "ddq";
    case InputKind::P:
      return "p";
    case InputKind::DQR:
      return "dqr";
    case InputKind::DDQR:
      return "ddqr";
    case InputKind::S:
      return "s";
    case InputKind::F:
      return "f";
  }
  return "?";
}

/// A node index with a sign: the value of the Ref is (negative ? -1 : 1) * value(node).
class Ref {
 public:
  constexpr Ref() = default;
  constexpr Ref(int id, bool negative)
      : bits_((static_cast<std::uint32_t>(id) << 1) | (negative ? 1u : 0u)) {}
  constexpr int id() const { return static_cast<int>(bits_ >> 1); }
  constexpr bool negative() const { return bits_ & 1u; }
  constexpr Ref operator-() const { return fromBits(bits_ ^ 1u); }
  constexpr Ref abs() const { return fromBits(bits_ & ~1u); }
  /// This Ref negated when `negate`.
  constexpr Ref negatedIf(bool negate) const { return negate ? -*this : *this; }
  constexpr std::uint32_t bits() const { return bits_; }
  static constexpr Ref fromBits(std::uint32_t b) {
    Ref r;
    r.bits_ = b;
    return r;
  }
  friend constexpr bool operator==(Ref a, Ref b) { return a.bits_ == b.bits_; }
  friend constexpr bool operator!=(Ref a, Ref b) { return a.bits_ != b.bits_; }

 private:
  std::uint32_t bits_ = 0;  // node 0 is the constant 0
};

struct Node {
  Op op = Op::Const;
  InputKind kind = InputKind::Q;  // Input
  int index = 0;                  // Input: joint or parameter index
  Ref a, b;                       // operands (Sin, Cos, Sign, Tanh, Exp: a only)
  double value = 0;               // Const
};

/// Operation counts of straight-line code.
struct OpCount {
  long mul = 0;   // multiplications
  long add = 0;   // additions and subtractions
  long neg = 0;   // negations left over at the outputs
  long trig = 0;  // sin and cos calls
  long sign = 0;  // sign() evaluations (Coulomb friction)
  long tanh = 0;  // tanh calls (smooth Coulomb friction)
  long exp = 0;   // exp calls (Stribeck friction)
  long total() const { return mul + add + neg + trig + sign + tanh + exp; }
};

/// Values of the inputs when a graph is evaluated.
struct InputValues {
  const double* q = nullptr;
  const double* dq = nullptr;
  const double* ddq = nullptr;
  const double* p = nullptr;
  const double* dqr = nullptr;
  const double* ddqr = nullptr;
  const double* s = nullptr;
  const double* f = nullptr;
};

class Graph {
 public:
  Graph();

  static constexpr Ref zero() { return Ref(0, false); }
  static constexpr Ref one() { return Ref(1, false); }

  Ref constant(double v);
  Ref input(InputKind kind, int index);
  Ref sin(Ref x);
  Ref cos(Ref x);
  Ref sign(Ref x);
  Ref tanh(Ref x);
  Ref exp(Ref x);
  Ref add(Ref a, Ref b);
  Ref sub(Ref a, Ref b) { return add(a, -b); }
  Ref mul(Ref a, Ref b);
  /// Sum of a list (left to right; empty: 0).
  Ref sum(const std::vector<Ref>& terms);

  bool isConstant(Ref r) const { return nodes_[r.id()].op == Op::Const; }
  /// Value of a constant Ref (sign applied); precondition isConstant(r).
  double constantValue(Ref r) const;
  const Node& node(int id) const { return nodes_[id]; }
  int size() const { return static_cast<int>(nodes_.size()); }

  /// Reference evaluation of every node (for tests and the runtime tape's checks).
  std::vector<double> evaluate(const InputValues& in) const;
  double value(const std::vector<double>& nodeValues, Ref r) const {
    return r.negative() ? -nodeValues[r.id()] : nodeValues[r.id()];
  }

 private:
  int intern(const Node& n);
  std::vector<Node> nodes_;
  std::unordered_map<std::uint64_t, std::vector<int>> table_;
};

/// The part of a graph that some outputs need, in evaluation order (dead code removed).
struct Program {
  std::vector<Ref> outputs;
  std::vector<int> order;  // nodes to compute (not constants or inputs), operands first
  std::vector<int> uses;   // per graph node: number of uses by scheduled nodes and outputs
  OpCount count;
};

Program schedule(const Graph& graph, const std::vector<Ref>& outputs);

/// A scalar handle for writing formulas with operators; every operation goes into `graph`.
struct Sym {
  Graph* g = nullptr;
  Ref r;
};
inline Sym operator+(Sym a, Sym b) { return {a.g, a.g->add(a.r, b.r)}; }
inline Sym operator-(Sym a, Sym b) { return {a.g, a.g->sub(a.r, b.r)}; }
inline Sym operator*(Sym a, Sym b) { return {a.g, a.g->mul(a.r, b.r)}; }
inline Sym operator-(Sym a) { return {a.g, -a.r}; }
inline Sym operator*(double c, Sym a) { return {a.g, a.g->mul(a.g->constant(c), a.r)}; }
inline Sym& operator+=(Sym& a, Sym b) { return a = a + b; }

}  // namespace mindyn::codegen
