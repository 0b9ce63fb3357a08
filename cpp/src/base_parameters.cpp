#include "mindyn/base_parameters.hpp"

#include <Eigen/QR>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <random>
#include <stdexcept>
#include <tuple>
#include <type_traits>

#include "mindyn/dynamics.hpp"
#include "mindyn/multibody.hpp"
#include "mindyn/projection.hpp"
#include "mindyn/recursive_base.hpp"
#include "mindyn/spatial.hpp"

namespace mindyn {

namespace {

// Vectors appended one after another, each kept as a dense segment from its first to its last
// non-zero entry or as its non-zero entries, whichever takes less memory: the pivots and residuals
// of the elimination are short segments on the projection's coordinates, dense on sampled
// regressors and scattered over the rows of a link's ancestors on the recursive method's rows.
class VectorPool {
 public:
  // Appends x(0 .. end - 1).
  void push(const Eigen::VectorXd& x, long end) {
    long first = 0, nnz = 0;
    while (first < end && x[first] == 0.0) ++first;
    for (long r = first; r < end; ++r) nnz += x[r] != 0.0;
    Item it{static_cast<long>(values_.size()), static_cast<long>(index_.size()), first, end, 0};
    if (8 * (end - first) <= 12 * nnz) {
      values_.insert(values_.end(), x.data() + first, x.data() + end);
    } else {
      it.sparse = nnz;
      for (long r = first; r < end; ++r)
        if (x[r] != 0.0) {
          index_.push_back(static_cast<int>(r));
          values_.push_back(x[r]);
        }
    }
    items_.push_back(it);
  }
  // x -= f * vector i (x long enough).
  void subtract(int i, double f, Eigen::Ref<Eigen::VectorXd> x) const {
    const Item& it = items_[i];
    if (!it.sparse) {
      x.segment(it.first, it.end - it.first).noalias() -=
          f * Eigen::Map<const Eigen::VectorXd>(values_.data() + it.at, it.end - it.first);
      return;
    }
    for (long k = 0; k < it.sparse; ++k) x[index_[it.ix + k]] -= f * values_[it.at + k];
  }
  // x(0 .. end - 1) = vector i, x(end ..) untouched.
  void load(int i, Eigen::Ref<Eigen::VectorXd> x) const {
    const Item& it = items_[i];
    x.head(it.end).setZero();
    subtract(i, -1.0, x);
  }
  long end(int i) const { return items_[i].end; }

 private:
  struct Item {
    long at, ix, first, end, sparse;  // sparse: number of entries kept, 0 for a dense segment
  };
  std::vector<Item> items_;
  std::vector<double> values_;
  std::vector<int> index_;
};

// Gaussian elimination of the columns of Z in `order` with partial pivoting; returns the rank.
// With `out`, also the decision and Y. Each column is reduced against the pivots before it:
//   z_c = sum_b f(b, c) u_b + x_c,
// x_c being zero on the pivot rows of those pivots; a column with a large enough residual x_c
// becomes pivot u_b = x_c (f(b, c) = 1). Y solves the square system on the pivot rows,
// Z~[prow] Y = Z[prow]: the residual of a dependent column is reduced further against the
// pivots found after it, so that it vanishes on every pivot row (the residual of a column
// dependent only within the tolerance is not zero there); then with F~ = F(:, pivots) (unit
// upper triangular), Y = F~^-1 F, which needs no separate factorization. Z, the pivots u_b, F
// and Y are kept sparse: on the recursive method's rows of a long tree they are mostly zero.
// Sizes are measured two ways: relative to the column's own norm (colmax), and entry by entry
// relative to the entry's row in the units of the parameters (`inv_row` = 1 / row size, `units`:
// see columnUnits), which tells a residual that is rounding noise of large terms from a small
// genuine one. `colsize` is the latter of each column, `zero_level` the size up to which a column
// counts as zero.
double sizeInRows(const Eigen::Ref<const Eigen::VectorXd>& x, long end,
                  const Eigen::VectorXd& inv_row, double unit) {
  return end > 0 ? x.head(end).cwiseAbs().cwiseProduct(inv_row.head(end)).maxCoeff() / unit : 0.0;
}

// `inv_scale` is 1 / the largest row (in the same units): a residual is kept only when it is also
// above the tolerance against it, the scale of the whole robot. A row is measured against itself
// to tell rounding noise from genuine small entries, but a row that is all small (the potential
// energy's coefficients on an axis tilted 1e-12 off vertical, gravity times the tilt) is no
// measure of what is numerically zero: the regressor's torques mix it with the large rows, and no
// rank decision on them resolves it. `kept` (optional) receives the pivots.
int eliminate(const Eigen::SparseMatrix<double>& Z, const std::vector<int>& order, double tol,
              const Eigen::VectorXd& colmax, const std::vector<long>& colend,
              const Eigen::VectorXd& inv_row, double inv_scale, const Eigen::VectorXd& units,
              const Eigen::VectorXd& colsize, double zero_level, RankDecision* out,
              std::vector<int>* kept = nullptr) {
  // Rows are kept in their order; every vector remembers where its non-zero part ends, since
  // the row reduction leaves the rows of the inner links first.
  const long m = Z.rows();
  const int P = static_cast<int>(Z.cols());
  const long most = std::min<long>(m, P);  // pivots at most
  VectorPool U;                            // the pivots u_b
  std::vector<double> upivot;              // u_b on its pivot row
  std::vector<long> uend;
  std::vector<int> prow;
  struct Factor {
    int b;
    double f;
  };
  std::vector<std::vector<Factor>> F;  // F(b, c) by column, b ascending
  if (out) F.resize(P);
  // Reduces x (non-zero up to `end`), the residual of column c, against pivots from .. to - 1.
  auto reduce = [&](Eigen::VectorXd& x, long& end, int c, int from, int to) {
    for (int b = from; b < to; ++b) {
      const double xb = prow[b] < end ? x[prow[b]] : 0.0;
      if (xb == 0.0) continue;  // (most entries, on structured coordinates: skip the division)
      const double f = xb / upivot[b];
      if (f == 0.0) continue;
      if (out) F[c].push_back({b, f});
      const long e = uend[b];
      if (e > end) {
        x.segment(end, e - end).setZero();
        end = e;
      }
      U.subtract(b, f, x);
    }
  };
  struct Dependent {
    int c, pivots;  // the column and the number of pivots before it
  };
  std::vector<Dependent> dependent;
  VectorPool residuals;  // of the dependent columns
  Eigen::VectorXd x(m);
  for (int c : order) {
    if (colsize[c] <= zero_level) {
      if (out) out->zero.push_back(c);
      continue;
    }
    long end = colend[c];
    x.head(end).setZero();
    for (Eigen::SparseMatrix<double>::InnerIterator it(Z, c); it; ++it) x[it.index()] = it.value();
    const int nb = static_cast<int>(prow.size());
    reduce(x, end, c, 0, nb);
    Eigen::Index r = 0;
    const double rel = end > 0 ? x.head(end).cwiseAbs().maxCoeff(&r) / colmax[c] : 0.0;
    // A matrix of m rows has at most min(m, P) pivots; a residual left once they are all taken
    // is rounding noise, so the column is dependent.
    // A residual small against its rows is dependent too, however large against its own column
    // (a column that is itself tiny: its coordinates carry the rounding of their rows).
    // (the size against the robot's largest row and against the column's rows are evaluated
    // only for a column that passes the first test)
    double size = 0;
    if (rel > tol && nb < most) {
      size = std::min(rel, sizeInRows(x, end, inv_row, units[c]));
      if (inv_scale > 0) size = std::min(size, rel * colmax[c] * inv_scale / units[c]);
    }
    if (size > tol) {
      if (kept) kept->push_back(c);
      U.push(x, end);
      upivot.push_back(x[r]);
      uend.push_back(end);
      prow.push_back(static_cast<int>(r));
      if (out) {
        F[c].push_back({nb, 1.0});
        out->pivots.push_back(c);
        out->pivot_size.push_back(rel);
        out->smallest_kept = std::min(out->smallest_kept, size);
      }
    } else if (out) {
      out->dependent.push_back(c);
      out->residual.push_back(rel);
      out->largest_dropped = std::max(out->largest_dropped, rel);
      residuals.push(x, end);
      dependent.push_back({c, nb});
    }
  }
  const int nb = static_cast<int>(prow.size());
  if (out) {
    for (std::size_t i = 0; i < dependent.size(); ++i) {
      const Dependent& d = dependent[i];
      long end = residuals.end(static_cast<int>(i));
      residuals.load(static_cast<int>(i), x);
      reduce(x, end, d.c, d.pivots, nb);
    }
    // Y = F~^-1 F by back substitution, column by column; pivot columns give e_b.
    std::vector<int> pivot_of(P, -1);
    for (int b = 0; b < nb; ++b) pivot_of[out->pivots[b]] = b;
    std::vector<Eigen::Triplet<double>> entries;
    Eigen::VectorXd y(nb);
    for (int c = 0; c < P; ++c) {
      if (pivot_of[c] >= 0) {
        entries.emplace_back(pivot_of[c], c, 1.0);
        continue;
      }
      if (F[c].empty()) continue;
      y.setZero();
      for (const Factor& e : F[c]) y[e.b] = e.f;
      for (int b = F[c].back().b; b > 0; --b) {
        const double yb = y[b];
        if (yb == 0.0) continue;
        for (const Factor& e : F[out->pivots[b]])
          if (e.b < b) y[e.b] -= e.f * yb;
      }
      for (int b = 0; b < nb; ++b)
        if (y[b] != 0.0) entries.emplace_back(b, c, y[b]);
    }
    out->Y.resize(nb, P);
    out->Y.setFromTriplets(entries.begin(), entries.end());
  }
  return nb;
}

std::string shortest(double v) {
  if (v == 0.0) v = 0.0;  // a negative zero prints as 0, not -0
  char buf[64];
  auto res = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, res.ptr);
}

std::string regroupedName(const std::string& classical) {
  size_t d = classical.size();
  while (d > 0 && std::isdigit(static_cast<unsigned char>(classical[d - 1]))) --d;
  return classical.substr(0, d) + "R" + classical.substr(d);
}

BaseSet makeSet(RankDecision decision, const std::vector<std::string>& names) {
  BaseSet set;
  const int nb = decision.rank();
  // Non-zero entries of each row of Y, counted column by column (Y is stored by columns).
  std::vector<long> nonzero(nb, 0);
  const Eigen::SparseMatrix<double>& Y = decision.Y;
  for (long c = 0; c < Y.cols(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(Y, c); it; ++it) ++nonzero[it.row()];
  set.names.reserve(nb);
  for (int b = 0; b < nb; ++b) {
    const int p = decision.pivots[b];
    const long others = nonzero[b] - (Y.coeff(b, p) != 0.0 ? 1 : 0);
    set.names.push_back(others > 0 ? regroupedName(names[p]) : names[p]);
  }
  set.decision = std::move(decision);
  return set;
}

double robotLength(const Model& model);

// The rates of the sampled states, per velocity coordinate: those of the unit-length model
// (unitLengthModel: lengths in L, time in sqrt(L / 1 m) s, gravity kept), so that gravity weighs
// against the motions as on the same shape a metre long, whatever the robot's size, as in the
// exact methods. A rotation's rate and acceleration are scaled by 1 / tau and 1 / tau^2, a
// translation's by L / tau and L / tau^2 (tau = sqrt(L)). (At rates of 1 rad/s a robot of 1e5 m
// weighed gravity by g / L against its motions: a first moment only gravity reveals, on an axis
// 4e-6 rad off vertical, fell under the rank tolerance.)
struct StateScale {
  Eigen::VectorXd velocity, acceleration;
  explicit StateScale(const Model& model) {
    const double L = robotLength(model), tau = std::sqrt(L);
    // per velocity coordinate, 't' for a translation, 'r' for a rotation (model.hpp, JointType)
    std::string kinds;
    for (const Joint& j : model.joints)
      kinds += j.type == JointType::Prismatic     ? "t"
               : j.type == JointType::Cylindrical ? "tr"
               : j.type == JointType::Planar      ? "ttr"
               : j.type == JointType::FreeFlyer
                   ? "tttrrr"
                   : std::string(static_cast<std::size_t>(j.nv()), 'r');
    const long nv = static_cast<long>(kinds.size());
    velocity.resize(nv);
    acceleration.resize(nv);
    for (long i = 0; i < nv; ++i) {
      const double length = kinds[static_cast<std::size_t>(i)] == 't' ? L : 1.0;
      velocity[i] = length / tau;
      acceleration[i] = length / (tau * tau);
    }
  }
  void apply(Eigen::VectorXd& dq, Eigen::VectorXd& ddq) const {
    dq.array() *= velocity.array();
    ddq.array() *= acceleration.array();
  }
};

// A random state: q within the joint limits (+-pi, or +-1 for a prismatic joint, where none are
// given), dq and ddq uniform in [-2, 2] in the time unit of the unit-length model (StateScale).
void randomState(const Model& model, std::mt19937& rng, Eigen::VectorXd& q, Eigen::VectorXd& dq,
                 Eigen::VectorXd& ddq, const StateScale& scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < model.nq(); ++k) {
    const JointLimits& l = model.joints[k].limits;
    const bool bounded = std::isfinite(l.lower) && std::isfinite(l.upper);
    const double lo =
        bounded ? l.lower : (model.joints[k].type == JointType::Revolute ? -kPi : -1.0);
    const double hi = bounded ? l.upper : -lo;
    q[k] = lo + (hi - lo) * 0.5 * (u(rng) + 1.0);
    dq[k] = 2.0 * u(rng);
    ddq[k] = 2.0 * u(rng);
  }
  scale.apply(dq, ddq);
}

// The regressor at a state of randomState (the rates of the unit-length model), its friction
// columns at the rates as given (those rates divided by the scale), `Wf` a work matrix of W's
// size. Friction has velocity scales of its own (a smooth or Stribeck width, in rad/s or m/s):
// at the rates of a robot of 1e5 m (1e-3 rad/s) tanh(v / w) is v / w to 1e-8, and its column
// would regroup with the viscous one. The friction columns are functions of the rates alone and
// independent of the link and rotor columns (which are polynomials of degree two in the rates),
// so that evaluating them at other rates of the same states keeps every dependency.
//
// A slot's scaled column (tanh(v / w), s exp(-(v / w)^2)) is t^T phi(v), t its row of T (e_k
// on the joint side) and v = t . dq its own rate: with T invertible the columns of distinct
// slots never combine, and the friction columns do not combine with the others, so the scaled
// column is independent of every other column whatever w. It is taken at v / u instead, u the
// largest entry of |t|, so that its sampled arguments spread over [-2, 2] whatever w: every
// slot's smooth or Stribeck column. At w far below the sampled speeds exp(-(v / w)^2) vanished (Fs
// dropped), far above them s exp(-(v / w)^2) was s to round-off (Fs regrouped with Fc) and
// tanh(v / w) was v / w (Fc regrouped with Fv); the exact methods keep them, and so does this.
void sampledRegressor(const Model& model, Data& data, ParameterLayout layout,
                      const Eigen::VectorXd& q, const Eigen::VectorXd& dq,
                      const Eigen::VectorXd& ddq, const StateScale& scale, MatOut W,
                      Eigen::MatrixXd& Wf) {
  regressor(model, data, q, dq, ddq, layout, W);
  if (!layout.friction) return;
  Wf.resize(W.rows(), W.cols());
  const Eigen::VectorXd dq0 = dq.cwiseQuotient(scale.velocity);
  const Eigen::VectorXd ddq0 = ddq.cwiseQuotient(scale.acceleration);
  regressor(model, data, q, dq0, ddq0, layout, Wf);
  for (int k = 0; k < model.nq(); ++k)
    for (int i = 0; i < layout.friction_columns; ++i)
      W.col(layout.frictionIndex(k, i)) = Wf.col(layout.frictionIndex(k, i));
  const FrictionKind kind = model.friction_model.kind;
  if (!model.friction_model.scaled()) return;
  const int scaled = kind == FrictionKind::Smooth ? 1 : 2;  // tanh(v / w); s exp(-(v / w)^2)
  for (int k = 0; k < model.nq(); ++k) {
    const double u = model.motorSide() ? model.transmission.T.row(k).cwiseAbs().maxCoeff() : 1.0;
    const double v = model.motorSide() ? model.transmission.T.row(k).dot(dq0) : dq0[k];
    const double r = v / u;
    const double phi = kind == FrictionKind::Smooth ? std::tanh(r) : sgn(v) * std::exp(-r * r);
    auto column = W.col(layout.frictionIndex(k, scaled));
    if (model.motorSide())
      column = phi * model.transmission.T.row(k).transpose();
    else {
      column.setZero();
      column[k] = phi;
    }
  }
}

// Some motor drives two or more joints (a row of T with two non-zero entries).
bool coupledMotors(const Eigen::MatrixXd& T) {
  for (Eigen::Index k = 0; k < T.rows(); ++k)
    if ((T.row(k).array() != 0.0).count() > 1) return true;
  return false;
}

// The dynamics the numerical method samples and the regrouping check evaluates, at a random
// state it holds: the single-DOF algorithms (dynamics.hpp) in the layout, or the multibody ones
// (multibody.hpp, inertial parameters only) on a model with multi-DOF joints.
struct Dynamics {
  Dynamics(const Model& m, ParameterLayout l)
      : model(m), layout(l), multi(!m.singleDof()), nv(m.velocitySize()), scale(m) {
    if (multi) {
      mb.emplace(model);
      q.resize(model.configSize());
    } else {
      data.emplace(model);
      q.resize(nv);
    }
    dq.resize(nv);
    ddq.resize(nv);
  }
  void randomState(std::mt19937& rng) {
    if (!multi) return mindyn::randomState(model, rng, q, dq, ddq, scale);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    randomConfiguration(model, rng, q);
    for (int i = 0; i < nv; ++i) {
      dq[i] = 2.0 * u(rng);
      ddq[i] = 2.0 * u(rng);
    }
    scale.apply(dq, ddq);
  }
  void regressor(MatOut W) {
    if (multi)
      mindyn::regressor(model, *mb, q, dq, ddq, W);
    else
      sampledRegressor(model, *data, layout, q, dq, ddq, scale, W, Wf);
  }
  void energyRegressors(VecOut wK, VecOut wP) {
    if (multi)
      mindyn::energyRegressors(model, *mb, q, dq, wK, wP);
    else
      mindyn::energyRegressors(model, *data, q, dq, layout, wK, wP);
  }
  void inverseDynamics(const VecRef& pi, VecOut tau) {
    if (multi)
      mindyn::inverseDynamics(model, *mb, q, dq, ddq, pi, tau);
    else
      mindyn::inverseDynamics(model, *data, q, dq, ddq, pi, layout, tau);
  }
  double kinetic(const VecRef& pi) {
    return multi ? kineticEnergy(model, *mb, q, dq, pi)
                 : kineticEnergy(model, *data, q, dq, pi, layout);
  }
  double potential(const VecRef& pi) {
    return multi ? potentialEnergy(model, *mb, q, pi)
                 : potentialEnergy(model, *data, q, pi, layout);
  }

  const Model& model;
  ParameterLayout layout;
  bool multi;
  int nv;
  StateScale scale;
  Eigen::MatrixXd Wf;  // the regressor at the rates as given, for the friction columns
  std::optional<Data> data;
  std::optional<MultibodyData> mb;
  Eigen::VectorXd q, dq, ddq;
};

// Samples of the regressors at random states, for the numerical method.
struct Samples {
  Eigen::MatrixXd W, wL, wH;
};

// `m` states give the regressor rows (n each); the energy rows (one per state) come from the
// first `me` states and further ones when me > m.
Samples sampleRegressors(const Model& model, ParameterLayout layout, int m, int me, unsigned seed) {
  const int P = layout.size(model.nq());
  Dynamics dyn(model, layout);
  const int n = dyn.nv;  // regressor rows per state
  std::mt19937 rng(seed);
  Samples s;
  s.W.resize(static_cast<long>(m) * n, P);
  s.wL.resize(me, P);
  s.wH.resize(me, P);
  Eigen::VectorXd wK(P), wP(P);
  Eigen::MatrixXd W(n, P);
  // Friction that is constant while a joint moves (the asymmetric model's Fa |sign v|) differs
  // from a constant torque (a prismatic joint's weight) only at rest: every fourth state of the
  // regressor rows is at rest then.
  const bool rests = layout.friction && model.friction_model.kind == FrictionKind::Asymmetric;
  for (int i = 0; i < std::max(m, me); ++i) {
    dyn.randomState(rng);
    if (i < me) {
      dyn.energyRegressors(wK, wP);
      s.wL.row(i) = (wK - wP).transpose();
      s.wH.row(i) = (wK + wP).transpose();
    }
    if (i < m) {
      if (rests && i % 4 == 0) dyn.dq.setZero();
      dyn.regressor(W);
      s.W.middleRows(static_cast<long>(i) * n, n) = W;
    }
  }
  return s;
}

// Z with its rows combined orthogonally within groups: a row whose basis function involves
// joints up to d only is zero on the columns of links before d (on a tree, its coordinates lie
// on the links joint d carries, all numbered after d), so a group of rows of equal
// depth (and of the same kind, potential or kinetic) reduces to at most as many rows as it has
// columns. Column dependencies, column 2-norms and Y = Z~+ Z are unchanged.
//
// Within a group, the rows with the same non-zero columns are combined first (a Householder QR
// of just those columns), which is cheap since most rows have one or a few entries; the rows that
// result are combined by a QR of the group's columns when there are more of them than columns. Rows
// without entries are left out.
struct Reduced {
  Eigen::MatrixXd Z;
  int constant_row = -1;  // the row of the constant function, if non-zero
};

Reduced reduceRows(const InfluenceCoordinates& ic) {
  const int P = ic.cols(), n = ic.n, G = 2 * (n + 1), rows = ic.rows();
  // The entries by row, by ascending column within a row.
  std::vector<int> start(rows + 1, 0);
  for (const auto& e : ic.entries) ++start[e.row + 1];
  for (int r = 0; r < rows; ++r) start[r + 1] += start[r];
  const int nnz = start[rows];
  std::vector<int> col(nnz);
  std::vector<double> val(nnz);
  bool sorted = true;
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (const auto& e : ic.entries) {
      const int k = fill[e.row]++;
      if (k > start[e.row] && col[k - 1] >= e.col) sorted = false;
      col[k] = e.col;
      val[k] = e.value;
    }
  }
  // The recursion projects a term link after link, ten forms in order, joints in index order
  // (on a tree too, for a row that several branches reach): it cannot do otherwise.
  if (!sorted) throw std::logic_error("projection: the coordinates of a row are out of order");

  std::vector<std::vector<int>> members(G);
  std::vector<int> first(G, P);
  for (int r = 0; r < rows; ++r) {
    if (start[r + 1] == start[r]) continue;
    const bool pot = (ic.keys[r] & 1023u) == 0;
    const int g = 2 * ic.depth(r) + (pot ? 1 : 0);
    members[g].push_back(r);
    first[g] = std::min(first[g], col[start[r]]);
  }
  // Rows of equal pattern (exact: a bit mask of the columns) are collected in buckets; a group
  // has few patterns, so they are searched linearly, starting from the last one found.
  if (P > kProjectionMaxParameters)  // refused before computing (projectionRefusal)
    throw std::logic_error("projection: more parameters than the row reduction's masks hold");
  std::vector<std::vector<int>> buckets;
  int nbuckets = 0;
  auto collect = [&](const std::vector<int>& rs, int offset, auto mask) {
    using Mask = decltype(mask);
    std::vector<Mask> masks;
    std::size_t hit = 0;
    for (int r : rs) {
      Mask m{};
      for (int e = start[r]; e < start[r + 1]; ++e) {
        const int c = col[e] - offset;
        if constexpr (std::is_same_v<Mask, std::uint64_t>)
          m |= std::uint64_t{1} << c;
        else
          m[c >> 6] |= std::uint64_t{1} << (c & 63);
      }
      if (hit >= masks.size() || masks[hit] != m) {
        hit = static_cast<std::size_t>(std::find(masks.begin(), masks.end(), m) - masks.begin());
        if (hit == masks.size()) {
          masks.push_back(m);
          if (buckets.size() < masks.size()) buckets.emplace_back();
          buckets[hit].clear();
        }
      }
      buckets[hit].push_back(r);
    }
    nbuckets = static_cast<int>(masks.size());
  };

  std::vector<Eigen::MatrixXd> blocks(G);
  Eigen::MatrixXd M;
  long total = 0;
  for (int g = 0; g < G; ++g) {
    const std::vector<int>& rs = members[g];
    if (rs.empty()) continue;
    const int width = P - first[g];
    if (width <= 64)
      collect(rs, first[g], std::uint64_t{0});
    else
      collect(rs, 0, std::array<std::uint64_t, kProjectionMaxParameters / 64>{});
    // Rows of equal pattern, combined: a bucket of k rows with s entries gives min(k, s) rows.
    long bound = 0;
    for (int i = 0; i < nbuckets; ++i) {
      const int r = buckets[i][0];
      bound += std::min<long>(static_cast<long>(buckets[i].size()), start[r + 1] - start[r]);
    }
    Eigen::MatrixXd B = Eigen::MatrixXd::Zero(bound, width);
    long used = 0;
    for (int i = 0; i < nbuckets; ++i) {
      const std::vector<int>& bucket = buckets[i];
      const int s0 = start[bucket[0]], s = start[bucket[0] + 1] - s0;
      const long k = static_cast<long>(bucket.size());
      if (k == 1) {
        for (int e = 0; e < s; ++e) B(used, col[s0 + e] - first[g]) = val[s0 + e];
        ++used;
      } else {
        M.resize(k, s);
        for (long t = 0; t < k; ++t)
          for (int e = 0; e < s; ++e) M(t, e) = val[start[bucket[t]] + e];
        Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(M);  // in place
        const long m = std::min<long>(k, s);
        for (long t = 0; t < m; ++t, ++used)
          for (int e = static_cast<int>(t); e < s; ++e) B(used, col[s0 + e] - first[g]) = M(t, e);
      }
    }
    if (used > width) {
      Eigen::Ref<Eigen::MatrixXd> top = B.topRows(used);
      Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(top);  // in place
      blocks[g] = B.topRows(width).triangularView<Eigen::Upper>();
    } else {
      blocks[g] = B.topRows(used);
    }
    total += blocks[g].rows();
  }
  Reduced out;
  out.Z = Eigen::MatrixXd::Zero(total, P);
  long row = 0;
  for (int g = 0; g < G; ++g) {
    if (blocks[g].size() == 0) continue;
    out.Z.block(row, first[g], blocks[g].rows(), blocks[g].cols()) = blocks[g];
    if (g == 1) out.constant_row = static_cast<int>(row);  // depth 0, potential: the constant
    row += blocks[g].rows();
  }
  return out;
}

}  // namespace

RankDecision echelon(const Eigen::MatrixXd& Z, const std::vector<int>& order, double tolerance,
                     const std::vector<int>& kinds, const Eigen::VectorXd& units, double scale) {
  return echelon(Eigen::SparseMatrix<double>(Z.sparseView(0.0, 0.0)), order, tolerance, kinds,
                 units, scale);
}

double largestRow(const Eigen::SparseMatrix<double>& Z, const Eigen::VectorXd& units) {
  double largest = 0;
  for (int c = 0; c < Z.cols(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(Z, c); it; ++it)
      largest = std::max(largest, std::abs(it.value()) / (units.size() ? units[c] : 1.0));
  return largest;
}

RankDecision echelon(const Eigen::SparseMatrix<double>& Z, const std::vector<int>& order,
                     double tolerance, const std::vector<int>& kinds,
                     const Eigen::VectorXd& units_in, double scale) {
  if (std::isnan(scale) || !std::isfinite(scale))
    throw std::invalid_argument("echelon: the scale must be a finite number");
  if (static_cast<long>(order.size()) != Z.cols())
    throw std::invalid_argument("echelon: the order must name every column once");
  if (units_in.size() != 0 && (units_in.size() != Z.cols() || !(units_in.array() > 0).all()))
    throw std::invalid_argument("echelon: units must be one positive number per column");
  std::vector<char> seen(Z.cols(), 0);
  for (int c : order) {
    if (c < 0 || c >= Z.cols() || seen[c])
      throw std::invalid_argument("echelon: the order must be a permutation");
    seen[c] = 1;
  }
  const Eigen::VectorXd units = units_in.size() ? units_in : Eigen::VectorXd::Ones(Z.cols()).eval();
  RankDecision d;
  d.tolerance = tolerance;
  Eigen::VectorXd colmax(Z.cols());
  std::vector<long> colend(Z.cols());                   // one past the last non-zero entry
  Eigen::VectorXd e = Eigen::VectorXd::Zero(Z.rows());  // a column at full length
  auto load = [&](int c) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(Z, c); it; ++it) e[it.index()] = it.value();
  };
  auto clear = [&](int c) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(Z, c); it; ++it) e[it.index()] = 0.0;
  };
  for (int c = 0; c < Z.cols(); ++c) {
    load(c);
    colmax[c] = e.norm();
    clear(c);
    long end = 0;
    for (Eigen::SparseMatrix<double>::InnerIterator it(Z, c); it; ++it)
      if (it.value() != 0.0) end = it.index() + 1;
    colend[c] = end;
  }
  // The size of each row in the units of the parameters, and of each column against its rows.
  Eigen::VectorXd inv_row = Eigen::VectorXd::Zero(Z.rows());
  for (int c = 0; c < Z.cols(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(Z, c); it; ++it)
      inv_row[it.index()] = std::max(inv_row[it.index()], std::abs(it.value()) / units[c]);
  // Rows at the rounding level of the largest (a basis function that is zero for the exact
  // geometry) count at that level.
  const double largest_row = Z.rows() ? inv_row.maxCoeff() : 0.0;
  // (a negative scale: none, the residuals measured against their columns and rows only)
  const double inv_scale = scale > 0         ? 1.0 / scale
                           : scale < 0       ? 0.0
                           : largest_row > 0 ? 1.0 / largest_row
                                             : 0.0;
  const double row_floor = 1e-13 * largest_row;
  for (long r = 0; r < Z.rows(); ++r)
    inv_row[r] = row_floor > 0 ? 1.0 / std::max(inv_row[r], row_floor) : 0.0;
  Eigen::VectorXd colsize(Z.cols());
  for (int c = 0; c < Z.cols(); ++c) {
    double size = 0;
    for (Eigen::SparseMatrix<double>::InnerIterator it(Z, c); it; ++it)
      size = std::max(size, std::abs(it.value()) * inv_row[it.index()]);
    colsize[c] = size / units[c];
  }
  constexpr double kZeroLevel = 1e-13;
  eliminate(Z, order, tolerance, colmax, colend, inv_row, inv_scale, units, colsize, kZeroLevel,
            &d);
  d.zero_threshold = kZeroLevel;
  for (int c : d.zero) d.largest_zeroed = std::max(d.largest_zeroed, colsize[c]);

  // Clean rounding in Y: coefficients that are 0 or +-1 to working precision are exactly that.
  // The level sits just above the rounding noise of exact geometry (<= 1e-13 relative): 1e-10
  // dropped genuine small coefficients of near-right-angle URDFs (1.3e-9 MZ5 in so101's ZZR1),
  // and W_b Y pi then missed the torques by 1e-10 relative; with 1e-12, by about 1e-12.
  constexpr double kCleanLevel = 1e-12;
  for (int c = 0; c < d.Y.cols(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(d.Y, c); it; ++it) {
      double& y = it.valueRef();
      const double rel = colmax[c] > 0 ? colmax[d.pivots[it.row()]] / colmax[c] : 1.0;
      if (std::abs(y) * rel < kCleanLevel || colsize[c] <= kZeroLevel)
        y = 0.0;
      else if (std::abs(std::abs(y) - 1.0) < kCleanLevel)
        y = y > 0 ? 1.0 : -1.0;
    }
  for (int b = 0; b < d.rank(); ++b) d.Y.coeffRef(b, d.pivots[b]) = 1.0;
  d.Y.prune([](Eigen::Index, Eigen::Index, double y) { return y != 0.0; });
  // The check: pivot columns are reproduced exactly (identity block of Y); the regrouped and the
  // zero ones by Z~ Y, whose evaluation rounds by about eps sum_b |Y(b, c)| |Z~(:, b)|. Only the
  // rows the column and its pivots touch are visited (e and a are zero elsewhere).
  {
    Eigen::VectorXd a = Eigen::VectorXd::Zero(Z.rows());
    std::vector<char> marked(Z.rows(), 0);
    std::vector<long> touched;
    constexpr double kEval = 4 * std::numeric_limits<double>::epsilon();
    double worst = 0;
    auto add = [&](int col, double y) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(Z, col); it; ++it) {
        const long r = it.index();
        if (!marked[r]) {
          marked[r] = 1;
          touched.push_back(r);
        }
        e[r] -= y * it.value();
        a[r] += std::abs(y * it.value());
      }
    };
    auto check = [&](int c, bool regrouped) {
      add(c, -1.0);
      for (Eigen::SparseMatrix<double>::InnerIterator y(d.Y, c); y; ++y)
        add(d.pivots[y.row()], y.value());
      double norm2 = 0, size = 0;
      for (long r : touched) {
        norm2 += e[r] * e[r];
        size = std::max(size, (std::abs(e[r]) + kEval * a[r]) * inv_row[r]);
        e[r] = a[r] = 0.0;
        marked[r] = 0;
      }
      touched.clear();
      size /= units[c];
      // (fit_residual: the regrouped columns; a zero column's is its own size, 1.)
      if (regrouped) d.fit_residual = std::max(d.fit_residual, std::sqrt(norm2) / colmax[c]);
      if (size > worst) {
        worst = size;
        d.worst_column = c;
      }
    };
    for (int c : d.dependent) check(c, true);
    for (int c : d.zero) check(c, false);
  }
  // Near-degenerate geometry: say what the neighbouring tolerances would decide.
  const double looser = tolerance * 1e4, tighter = tolerance * 1e-3;
  int weak = 0;
  std::vector<char> weak_column(Z.cols(), 0);
  if (kinds.size() == static_cast<size_t>(Z.cols())) {
    std::vector<double> kindmax(*std::max_element(kinds.begin(), kinds.end()) + 1, 0.0);
    for (int c = 0; c < Z.cols(); ++c)
      kindmax[kinds[c]] = std::max(kindmax[kinds[c]], colmax[c] / units[c]);
    for (int b = 0; b < d.rank(); ++b) {
      const int c = d.pivots[b];
      const double s = d.pivot_size[b] * colmax[c] / units[c] / kindmax[kinds[c]];
      d.weakest_kept = std::min(d.weakest_kept, s);
      if (s < looser) {
        ++weak;
        weak_column[c] = 1;
      }
    }
  }
  if (d.smallest_kept < looser * 10 || d.largest_dropped > tighter / 10 || weak > 0 ||
      d.largest_zeroed > 0) {
    // Each decision depends only on those before it: with every kept pivot above the looser
    // tolerance, or every dropped residual below the tighter one and no column zeroed that is
    // not exactly zero, the elimination would decide every column as it did.
    std::vector<int> at_looser, at_tighter;
    d.rank_looser = d.smallest_kept > looser
                        ? d.rank()
                        : eliminate(Z, order, looser, colmax, colend, inv_row, inv_scale, units,
                                    colsize, kZeroLevel, nullptr, &at_looser);
    // At the tighter tolerance, near the rounding of the coordinates, the columns are measured
    // against their own rows only: the count says what the coordinates resolve at all, as the
    // other methods' counts there do (the robot's scale would hide a column of 1e-12 behind
    // the largest row, where the sampled regressor resolves it).
    d.rank_tighter = d.largest_dropped <= tighter && d.largest_zeroed == 0 && inv_scale == 0
                         ? d.rank()
                         : eliminate(Z, order, tighter, colmax, colend, inv_row, 0.0, units,
                                     colsize, 0.0, nullptr, &at_tighter);
    if (d.smallest_kept > looser) at_looser = d.pivots;
    if (d.rank_tighter == d.rank() && at_tighter.empty()) at_tighter = d.pivots;
    // Weak columns would go at the looser tolerance measured against their kind.
    d.rank_looser = std::min(d.rank_looser, d.rank() - weak);
    // The parameters the decision affects: base at one neighbouring tolerance and not at the
    // other, or weak.
    std::vector<char> here(Z.cols(), 0), loose(Z.cols(), 0), tight(Z.cols(), 0);
    for (int c : d.pivots) here[c] = 1;
    for (int c : at_looser) loose[c] = 1;
    for (int c : at_tighter) tight[c] = 1;
    for (int c = 0; c < Z.cols(); ++c)
      if (weak_column[c]) loose[c] = 0;
    for (int c : order)
      if (here[c] != loose[c] || here[c] != tight[c]) d.undecided.push_back(c);
  } else {
    d.rank_looser = d.rank_tighter = d.rank();
  }
  d.near_degenerate = d.rank_looser != d.rank() || d.rank_tighter != d.rank();
  return d;
}

namespace {

// The robot's length: the longest root path, joint offsets and prismatic travel added up, as a
// power of two (so that scaling by it is exact); 1 m for a robot without lengths.
double robotLength(const Model& model) {
  const int n = model.nq();
  std::vector<double> path(n, 0.0);
  double reach = 0;
  for (int k = 0; k < n; ++k) {
    const Joint& j = model.joints[k];
    double travel = 0;
    if (j.type == JointType::Prismatic) {
      const bool bounded = std::isfinite(j.limits.lower) && std::isfinite(j.limits.upper);
      travel = bounded ? std::max(std::abs(j.limits.lower), std::abs(j.limits.upper)) : 1.0;
    }
    const int p = model.parent(k);
    path[k] = (p >= 0 ? path[p] : 0.0) + j.pre.translation().norm() + j.post.translation().norm() +
              travel;
    reach = std::max(reach, path[k]);
  }
  return reach > 0 && std::isfinite(reach) ? std::exp2(std::round(std::log2(reach))) : 1.0;
}

// The model with every length divided by L (a power of two: exact) and gravity kept, so that
// the exact methods form their coordinates at lengths of order one: their pruning of rounding
// noise compares entries of a term that mix lengths to the first and second power, which at
// kilometres or micrometres drops genuine entries. Gravity kept is the model in the time unit
// sqrt(L / 1 m) s: the potential rows weigh against the kinetic ones as on the same shape a metre
// long, whatever its size. (Gravity divided by L weighed them by g / L: on a robot of 1e5 m a
// column set apart by gravity alone, a prismatic rotor inertia beside its link's mass on an axis
// 1e-5 rad off horizontal, fell under the rank tolerance in the projection method and not in the
// recursive one, which measures directions.) Coordinates of the scaled model times the column
// units (columnUnits) are those of the model, row for row up to a factor per row (a power of L,
// and of the time unit for the kinetic rows): the same ranks and the same Y.
Model unitLengthModel(const Model& model, double L) {
  Model m = model;
  for (int k = 0; k < m.nq(); ++k) {
    Joint& j = m.joints[k];
    j.pre.translation() /= L;
    j.post.translation() /= L;
    if (j.type == JointType::Prismatic) {
      j.limits.lower /= L;
      j.limits.upper /= L;
      // a joint's speed scale, m/s (a motor's, on the motor side, keeps its motor units)
      if (m.friction_model.scaled() && !m.motorSide()) m.friction_model.velocity[k] /= L;
    }
  }
  m.tool.translation() /= L;
  // Motor positions per joint length: a prismatic joint's column of T in motor units per L, so
  // that the motors' positions, velocities and terms keep their units (column unit 1).
  if (!m.transmission.empty())
    for (int k = 0; k < m.nq(); ++k)
      if (m.joints[k].type == JointType::Prismatic) m.transmission.T.col(k) *= L;
  return m;
}

}  // namespace

Eigen::VectorXd columnUnits(const Model& model, ParameterLayout layout) {
  const int n = model.nq();
  const double L = robotLength(model);
  Eigen::VectorXd units = Eigen::VectorXd::Ones(layout.size(n));
  for (int k = 0; k < n; ++k) {
    const int c0 = k * layout.perLink();
    for (int i = 6; i < 9; ++i) units[c0 + i] = L;  // MX MY MZ
    units[c0 + 9] = L * L;                          // M
    // A prismatic joint's rotor inertia and friction act on its force as a mass does. A motor's
    // (the motor side) keep their units: the scaled model's T carries the length of the
    // prismatic joints it drives (unitLengthModel).
    const bool prismatic = model.joints[k].type == JointType::Prismatic && !model.motorSide();
    if (prismatic)
      for (int c = c0 + 10; c < c0 + layout.perLink(); ++c) units[c] = L * L;
    // Friction is sampled at the rates as given and the link columns at those of the
    // unit-length model (StateScale): a revolute joint's friction measures against its
    // accelerations, smaller by 1 / L, as a prismatic joint's does against its mass.
    for (int i = 0; layout.friction && !prismatic && i < layout.friction_columns; ++i)
      units[layout.frictionIndex(k, i)] = L;
  }
  return units;
}

namespace {

// The size of each column's coordinates for a parameter of the size it takes in the torques of
// the unit-length model: columnUnits, and on the motor side a drive-train parameter's torques
// through its motor's reduction r (the largest entry of its row of T in that model, as a power
// of two), T^T Ia T ddq and T^T Fv T dq by r^2, the bounded friction shapes by r. The decisions
// measure the columns in these sizes; the coordinates are formed with columnUnits (so that Y
// is the model's). A rotor on a reduction of 52143 rad/m measured in columnUnits was 2.7e9 times
// the joint-side columns of its rows, which then fell under the tolerance against them.
Eigen::VectorXd parameterSizes(const Model& model, ParameterLayout layout) {
  Eigen::VectorXd sizes = columnUnits(model, layout);
  if (!model.motorSide() || (!layout.rotor && !layout.friction)) return sizes;
  const int n = model.nq();
  const Eigen::MatrixXd& T = model.transmission.T;
  const double L = robotLength(model);
  for (int k = 0; k < n && k < T.rows(); ++k) {
    // motor k's largest reduction in the unit-length model (a prismatic joint's column of T in
    // motor units per L, unitLengthModel), as a power of two
    double r = 0;
    for (int a = 0; a < n; ++a)
      r = std::max(r, std::abs(T(k, a)) * (model.joints[a].type == JointType::Prismatic ? L : 1));
    if (!(r > 0) || !std::isfinite(r)) continue;
    const double s = std::exp2(std::round(std::log2(r)));
    if (layout.rotor) sizes[layout.rotorIndex(k)] *= s * s;
    for (int i = 0; layout.friction && i < layout.friction_columns; ++i)
      sizes[layout.frictionIndex(k, i)] *= i == 0 ? s * s : s;
  }
  return sizes;
}

}  // namespace

std::vector<int> khalilOrder(int n, ParameterLayout layout) {
  std::vector<int> order;
  for (int k = 0; k < n; ++k) {
    const int c0 = k * layout.perLink();
    for (int p : {0, 1, 2, 4, 5, 6, 7, 3, 8, 9}) order.push_back(c0 + p);
    if (layout.rotor) order.push_back(layout.rotorIndex(k));
    for (int i = 0; layout.friction && i < layout.friction_columns; ++i)
      order.push_back(layout.frictionIndex(k, i));
  }
  for (int k = 0; layout.offset && k < n; ++k) order.push_back(layout.offsetIndex(n, k));
  return order;
}

std::string formatFormula(const std::string& name, const Eigen::Ref<const Eigen::RowVectorXd>& row,
                          const std::vector<std::string>& classical_names) {
  std::string s;
  s.reserve(name.size() + 64);
  s += name;
  s += " =";
  bool first = true;
  char buf[32];
  for (int c = 0; c < row.size(); ++c) {
    const double y = row[c];
    if (y == 0.0) continue;
    const bool neg = y < 0;
    const double a = std::abs(y);
    s += first ? (neg ? " -" : " ") : (neg ? " - " : " + ");
    if (a != 1.0) {
      s.append(buf, std::to_chars(buf, buf + sizeof(buf), a).ptr);
      s += '*';
    }
    s += classical_names[c];
    first = false;
  }
  if (first) s += " 0";
  return s;
}

std::vector<std::string> BaseSet::formulas(const std::vector<std::string>& classical_names) const {
  if (static_cast<long>(classical_names.size()) != decision.Y.cols())
    throw std::invalid_argument("formulas: " + std::to_string(classical_names.size()) +
                                " classical names for " + std::to_string(decision.Y.cols()) +
                                " columns of Y");
  std::vector<std::string> out;
  out.reserve(names.size());
  const Eigen::SparseMatrix<double, Eigen::RowMajor> rows = decision.Y;  // the rows, contiguous
  Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(rows.cols());
  for (int b = 0; b < size(); ++b) {
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(rows, b); it; ++it)
      row[it.col()] = it.value();
    out.push_back(formatFormula(names[b], row, classical_names));
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(rows, b); it; ++it)
      row[it.col()] = 0.0;
  }
  return out;
}

Eigen::VectorXd BaseParameters::values(const Eigen::Ref<const Eigen::VectorXd>& classical) const {
  if (classical.size() != eom.decision.Y.cols())
    throw std::invalid_argument("classical parameter vector has " +
                                std::to_string(classical.size()) + " entries; expected " +
                                std::to_string(eom.decision.Y.cols()));
  return eom.decision.Y * classical;
}

Eigen::VectorXd BaseParameters::embed(const Eigen::Ref<const Eigen::VectorXd>& base) const {
  if (base.size() != eom.size())
    throw std::invalid_argument("base parameter vector has " + std::to_string(base.size()) +
                                " entries; expected " + std::to_string(eom.size()));
  Eigen::VectorXd pi = Eigen::VectorXd::Zero(eom.decision.Y.cols());
  for (int b = 0; b < eom.size(); ++b) pi[eom.decision.pivots[b]] = base[b];
  return pi;
}

namespace {

// The recursion decides ranks of its own, on spans of at most ten dimensions: their margins join
// those of the echelon form, and when one is close, the counts at the neighbouring tolerances
// (and with them the near-degenerate flag) come from the recursion run again at those tolerances
// (its rows are independent by construction, so their number is the rank; the Lagrangian's count
// moves with it).
// The recursion's rows with the columns in their units, then each row normalised (its norm
// summed in column order) with its entries measured in `sizes` (parameterSizes), as the
// decisions measure them: a row holding a rotor on a large reduction is of that size.
Eigen::SparseMatrix<double> recursiveCoordinates(Eigen::SparseMatrix<double> Z,
                                                 const Eigen::VectorXd& units,
                                                 const Eigen::VectorXd& sizes) {
  Eigen::VectorXd norm2 = Eigen::VectorXd::Zero(Z.rows());
  for (int c = 0; c < Z.cols(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(Z, c); it; ++it) {
      it.valueRef() *= units[c];
      norm2[it.row()] += (it.value() / sizes[c]) * (it.value() / sizes[c]);
    }
  for (int c = 0; c < Z.cols(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(Z, c); it; ++it)
      it.valueRef() /= std::sqrt(norm2[it.row()]);
  return Z;
}

// `count(t)`: the number of base parameters with the recursion at tolerance t, `rows` at tol, and
// the equations-of-motion pivots at t (those whose decision changes join `undecided`).
template <class Count>
void foldRecursiveMargins(double tol, const IdentifiableSpace& space, long rows, Count count,
                          const std::vector<int>& order, BaseParameters& bp) {
  const double looser = tol * 1e4, tighter = tol * 1e-3;
  const bool close = space.smallest_kept < looser * 10 || space.largest_dropped > tighter / 10;
  int dl = 0, dt = 0;
  std::vector<char> changed(bp.classical_names.size(), 0);
  if (close) {
    std::vector<char> here(changed.size(), 0);
    for (int c : bp.eom.decision.pivots) here[c] = 1;
    for (double t : {looser, tighter}) {
      const auto [count_t, pivots_t] = count(t);
      (t == looser ? dl : dt) = static_cast<int>(count_t - rows);
      std::vector<char> there(changed.size(), 0);
      for (int c : pivots_t) there[c] = 1;
      for (std::size_t c = 0; c < changed.size(); ++c) changed[c] |= here[c] != there[c];
    }
  }
  for (BaseSet* set : {&bp.lagrangian, &bp.energy, &bp.eom}) {
    RankDecision& d = set->decision;
    d.smallest_kept = std::min(d.smallest_kept, space.smallest_kept);
    d.largest_dropped = std::max(d.largest_dropped, space.largest_dropped);
    if (!close) continue;
    d.rank_looser = std::min(d.rank_looser, d.rank() + dl);
    d.rank_tighter = std::max(d.rank_tighter, d.rank() + dt);
    d.near_degenerate = d.rank_looser != d.rank() || d.rank_tighter != d.rank();
    for (int c : d.undecided) changed[c] = 1;
    d.undecided.clear();
    for (int c : order)
      if (changed[c]) d.undecided.push_back(c);
  }
}

// The check of each set against the classical dynamics, independent of the method's own
// coordinates: at random states and for random classical vectors pi (each parameter of the size
// its column's units make comparable), the inverse dynamics of pi against that of the classical
// vector holding Y pi at the pivots (the equations-of-motion set), and likewise the Lagrangian
// and the total energy; the largest difference relative to the largest value is stored in each
// decision's `consistency`.
void checkRegrouping(const Model& model, ParameterLayout layout, const Eigen::VectorXd& units,
                     BaseParameters& bp) {
  const int P = layout.size(model.nq());
  Dynamics dyn(model, layout);
  const int n = dyn.nv;
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  constexpr int kStates = 10, kVectors = 3;
  // The vectors pi, and for each set the classical vectors holding Y pi at its pivots: one
  // sparse product with Y per set, so that the check costs a few inverse-dynamics and energy
  // evaluations (linear in the joints) beside it.
  Eigen::MatrixXd pis(P, kVectors);
  for (int v = 0; v < kVectors; ++v)
    for (int c = 0; c < P; ++c)
      pis(c, v) = (0.5 + 0.5 * std::abs(u(rng))) * (u(rng) < 0 ? -1 : 1) / units[c];
  BaseSet* sets[] = {&bp.eom, &bp.lagrangian, &bp.energy};
  Eigen::MatrixXd embedded[3];
  for (int i = 0; i < 3; ++i) {
    const RankDecision& d = sets[i]->decision;
    const Eigen::MatrixXd pb = d.Y * pis;
    embedded[i] = Eigen::MatrixXd::Zero(P, kVectors);
    for (int b = 0; b < d.rank(); ++b) embedded[i].row(d.pivots[b]) = pb.row(b);
  }
  double err[3] = {0, 0, 0}, size[3] = {0, 0, 0};
  Eigen::VectorXd tau(n), tau_b(n);
  for (int s = 0; s < kStates; ++s) {
    dyn.randomState(rng);
    for (int v = 0; v < kVectors; ++v) {
      const auto pi = pis.col(v);
      dyn.inverseDynamics(pi, tau);
      dyn.inverseDynamics(embedded[0].col(v), tau_b);
      err[0] = std::max(err[0], (tau - tau_b).cwiseAbs().maxCoeff());
      size[0] = std::max(size[0], tau.cwiseAbs().maxCoeff());
      const double K = dyn.kinetic(pi);
      const double V = dyn.potential(pi);
      for (int i = 1; i < 3; ++i) {
        const double Kb = dyn.kinetic(embedded[i].col(v));
        const double Vb = dyn.potential(embedded[i].col(v));
        const double e = i == 1 ? (K - V) - (Kb - Vb) : (K + V) - (Kb + Vb);
        err[i] = std::max(err[i], std::abs(e));
        size[i] = std::max(size[i], std::abs(K) + std::abs(V));
      }
    }
  }
  for (int i = 0; i < 3; ++i) sets[i]->decision.consistency = size[i] > 0 ? err[i] / size[i] : 0.0;
}

// Refuses a set whose regrouping does not reproduce the dynamics (see checkRegrouping).
void refuseInconsistent(const BaseParameters& bp, double tol) {
  // A few random vectors pi stand for every parameter vector, whose terms may be distributed
  // otherwise: the exact methods' torques are checked to a hundredth of the tolerance (a
  // physical vector's error was up to 100 times theirs on generated odd geometry), the energies
  // and the sampled method's sets, which fit to about 1e-11, to a tenth.
  const double eom_share = bp.method == BaseMethod::Numerical ? 0.1 : 0.01;
  const std::tuple<const BaseSet*, const char*, double> sets[] = {
      {&bp.eom, "equations of motion", eom_share},
      {&bp.lagrangian, "Lagrangian", 0.1},
      {&bp.energy, "total energy", 0.1}};
  for (const auto& [set, what, share] : sets) {
    const RankDecision& d = set->decision;
    if (!(d.consistency > share * tol)) continue;
    char buf[640];
    std::snprintf(
        buf, sizeof buf,
        "the %s base set (%d parameters at rank tolerance %s) does not reproduce the dynamics: "
        "at random states its regrouping misses the classical model by %.2g relative, over the "
        "tolerance (largest regrouping residual at %s); the geometry is near-degenerate "
        "(smallest kept pivot %.2g, largest regrouped residual %.2g; %d base parameters at "
        "tolerance %.2g, %d at %.2g)%s",
        what, d.rank(), shortest(tol).c_str(), d.consistency,
        d.worst_column >= 0 ? bp.classical_names[d.worst_column].c_str() : "no column",
        d.smallest_kept, d.largest_dropped, d.rank_looser, tol * 1e4, d.rank_tighter, tol * 1e-3,
        bp.snappable.empty()
            ? ": give a looser or tighter rank tolerance"
            : ": round the joint rotations and axes that are within 1e-3 of right angles (snap), "
              "or give another rank tolerance");
    throw ModelError(buf);
  }
}

// The sets of the link blocks (options.layout without the joint block).
BaseParameters linkBaseParameters(const Model& model, const BaseOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const int n = model.nq();
  const ParameterLayout layout = options.layout;
  const int P = layout.size(n);
  try {
    checkFrictionLayout(model, layout);
  } catch (const std::invalid_argument& e) {
    throw ModelError(e.what());
  }
  std::vector<int> order = options.order.empty() ? khalilOrder(n, layout) : options.order;
  if (static_cast<int>(order.size()) != P)
    throw ModelError("the parameter order names " + std::to_string(order.size()) +
                     " parameters; the layout has " + std::to_string(P));
  if (!model.singleDof()) {
    if (layout.rotor || layout.friction)
      throw ModelError(
          "rotor inertia and friction are defined for revolute and prismatic joints "
          "only; model '" +
          model.name + "' has multi-DOF joints");
  }
  checkDriveSide(model, layout);  // after: a multi-DOF joint has no motor
  if (!(options.tolerance > 0 && options.tolerance < 1e-2))
    throw ModelError("the rank tolerance must be in (0, 0.01), got " + shortest(options.tolerance));

  BaseParameters bp;
  bp.layout = layout;
  bp.method = options.method;
  bp.classical_names = model.parameterNames(layout);
  const double tol = options.tolerance;

  Eigen::SparseMatrix<double> ZL, ZH, ZE;
  IdentifiableSpace space;  // recursive method
  auto sparse = [](const Eigen::MatrixXd& Z) {
    return Eigen::SparseMatrix<double>(Z.sparseView(0.0, 0.0));
  };
  const Eigen::VectorXd units = columnUnits(model, layout);
  // the sizes the decisions measure the columns in (the motors' reductions on the drive-train
  // columns); `units` forms the coordinates, so that Y is the model's
  const Eigen::VectorXd sizes = parameterSizes(model, layout);
  const double length = robotLength(model);
  const Model unit_model = length != 1.0 ? unitLengthModel(model, length) : Model{};
  const Model& exact_model = length != 1.0 ? unit_model : model;
  // A model with multi-DOF joints: the exact methods run on its single-DOF expansion (each pair
  // a chain of single-DOF joints through massless links, expandToSingleDof), whose coordinates
  // on the real links' columns span the real model's (docs/base-parameters.md). The projection
  // method keeps a floating root as it is: its recursion takes the free body's twist and
  // gravity direction natively.
  const bool expand = !model.singleDof() && options.method != BaseMethod::Numerical;
  const SingleDofExpansion expansion =
      expand ? expandToSingleDof(exact_model, options.method == BaseMethod::Projection)
             : SingleDofExpansion{};
  const Model& kernel = expand ? expansion.model : exact_model;
  Eigen::SparseMatrix<double> real;  // the real links' columns of the expansion's
  if (expand) {
    std::vector<Eigen::Triplet<double>> ones;
    for (int c = 0; c < P; ++c)
      ones.emplace_back(expansion.column[static_cast<std::size_t>(c)], c, 1.0);
    real.resize(10 * kernel.nq(), P);
    real.setFromTriplets(ones.begin(), ones.end());
  }
  if (options.method == BaseMethod::Projection) {
    if (expand) {
      // the refusal of the model as given says how its multi-DOF joints were counted (the
      // expansion's alone named a joint count the model does not have)
      const std::string why = projectionRefusal(exact_model, layout, options.projection_budget);
      const std::string kernel_why = projectionRefusal(kernel, layout, options.projection_budget);
      if (!why.empty() && !kernel_why.empty()) {
        try {
          influenceCoordinates(kernel, layout, options.projection_budget);
        } catch (const ModelError& e) {
          const std::string what = e.what();
          if (what.rfind(kernel_why, 0) != 0) throw;
          throw ModelError(why + what.substr(kernel_why.size()));
        }
      }
    }
    const InfluenceCoordinates ic = influenceCoordinates(kernel, layout, options.projection_budget);
    bp.basis_rows = ic.rows();
    bp.terms_formed = ic.terms_formed;
    const Reduced red = reduceRows(ic);
    const Eigen::MatrixXd Zs =
        expand ? Eigen::MatrixXd(red.Z * real * units.asDiagonal()) : red.Z * units.asDiagonal();
    ZL = sparse(Zs);
    // Equations of motion: the constant does not reach the torques; friction columns do.
    const long keep = Zs.rows() - (red.constant_row >= 0 ? 1 : 0);
    const int fc = layout.friction ? layout.friction_columns : 0;
    const int fr = fc * n;
    Eigen::MatrixXd Z = Eigen::MatrixXd::Zero(keep + fr, P);
    long row = 0;
    for (long r = 0; r < Zs.rows(); ++r)
      if (r != red.constant_row) Z.row(row++) = Zs.row(r);
    // A friction parameter of unit size in the robot's scale (its column's size, with its
    // motor's reduction), as the other rows' coordinates are: the rows are measured against
    // the largest (echelon).
    auto unitRow = [&](int k, int i) {
      const int c = layout.frictionIndex(k, i);
      Z(keep + fc * k + i, c) = sizes[c];
    };
    if (fc > 0 && kernel.motorSide() && coupledMotors(kernel.transmission.T)) {
      // Friction of motors that couple joints: motor k's columns are functions of its velocity
      // T_k dq, so motors whose rows of T are nearly parallel have nearly dependent friction
      // columns (a unit row each counted them independent). The rows are the triangular factor
      // of those motors' friction columns sampled at random states, each column scaled to its
      // unit: the same dependencies, decided by the elimination as the other rows are (each
      // column scaled to its size, with its motor's reduction). A motor that alone drives one
      // joint alone (Transmission::soleJoint) shares that joint's torque with no other motor:
      // its columns are independent of every other's, a unit row each (sampled, a Stribeck
      // column at a velocity scale far below the sampled motor speeds vanished).
      std::vector<int> shared;
      for (int k = 0; k < n; ++k) {
        if (kernel.transmission.soleJoint(k) >= 0)
          for (int i = 0; i < fc; ++i) unitRow(k, i);
        else
          shared.push_back(k);
      }
      const int fs = fc * static_cast<int>(shared.size());
      Dynamics dyn(kernel, layout);
      std::mt19937 rng(options.seed);
      const int states = std::max(40, 2 * fs);
      const int nv = kernel.velocitySize();
      Eigen::MatrixXd F(static_cast<long>(states) * nv, fs), W(nv, P);
      for (int s = 0; s < states; ++s) {
        dyn.randomState(rng);
        dyn.regressor(W);
        for (std::size_t a = 0; a < shared.size(); ++a)
          for (int i = 0; i < fc; ++i)
            F.block(static_cast<long>(s) * nv, fc * static_cast<long>(a) + i, nv, 1) =
                W.col(layout.frictionIndex(shared[a], i));
      }
      for (std::size_t a = 0; a < shared.size(); ++a)
        for (int i = 0; i < fc; ++i) {
          const long col = fc * static_cast<long>(a) + i;
          const double norm = F.col(col).norm();
          if (norm > 0) F.col(col) *= sizes[layout.frictionIndex(shared[a], i)] / norm;
        }
      const Eigen::MatrixXd R = Eigen::HouseholderQR<Eigen::MatrixXd>(F).matrixQR().topRows(fs);
      for (int a = 0; a < fs; ++a)
        for (int b = a; b < fs; ++b)
          Z(keep + fc * shared[a / fc] + a % fc, layout.frictionIndex(shared[b / fc], b % fc)) =
              R(a, b);
    } else {
      for (int k = 0; k < n; ++k)
        for (int i = 0; i < fc; ++i) unitRow(k, i);
    }
    ZE = sparse(Z);
  } else if (options.method == BaseMethod::Recursive) {
    // The rows span the identifiable space exactly; the Lagrangian's adds its constant (and has
    // no friction columns), the total energy's is the same space.
    space = recursiveIdentifiable(kernel, layout, tol);
    if (expand) {
      ZE = recursiveCoordinates(space.rows * real, units, sizes);
      space.constant = space.constant * real;
    } else {
      ZE = recursiveCoordinates(std::move(space.rows), units, sizes);
    }
    space.constant = space.constant * units.asDiagonal();
    // normalised as the rows are, in the sizes (its size, gravity times a length, is no
    // measure of them)
    if (const double norm = space.constant.cwiseQuotient(sizes.transpose()).norm(); norm > 0)
      space.constant /= norm;
    // The constant first: it involves no joint, like the rows of the inner links, and leaves
    // the columns' last non-zero rows where they are. Then the rows with an entry off the
    // friction columns, without their friction entries.
    std::vector<char> friction(P, 0);
    for (int k = 0; k < n && layout.friction; ++k)
      for (int i = 0; i < layout.friction_columns; ++i) friction[layout.frictionIndex(k, i)] = 1;
    std::vector<long> kept(ZE.rows(), -1);  // a row's row in ZL
    for (int c = 0; c < P; ++c)
      if (!friction[c])
        for (Eigen::SparseMatrix<double>::InnerIterator it(ZE, c); it; ++it)
          if (it.value() != 0.0) kept[it.row()] = 0;
    long rowsL = 1;
    for (long& r : kept)
      if (r == 0) r = rowsL++;
    std::vector<Eigen::Triplet<double>> entries;
    for (int c = 0; c < P; ++c) {
      if (friction[c]) continue;
      if (space.constant[c] != 0.0) entries.emplace_back(0, c, space.constant[c]);
      for (Eigen::SparseMatrix<double>::InnerIterator it(ZE, c); it; ++it)
        if (it.value() != 0.0) entries.emplace_back(kept[it.row()], c, it.value());
    }
    ZL.resize(rowsL, P);
    ZL.setFromTriplets(entries.begin(), entries.end());
    bp.basis_rows = static_cast<int>(ZE.rows());
  } else {
    // The sampled matrices need at least as many rows as the rank they are to show (at most P
    // each), with a margin so that random states keep the smallest singular values clear of
    // the tolerance: the regressor stacks n rows per state, the energies one.
    const int m = options.samples > 0 ? options.samples : std::max(40, 3 * P / std::max(1, n) + 20);
    const int me = std::max(m, P + std::max(20, P / 2));
    const int nv = model.velocitySize();  // regressor rows per state
    if (static_cast<long>(m) * nv < P)
      throw ModelError("samples = " + std::to_string(m) + " states give " +
                       std::to_string(static_cast<long>(m) * nv) + " regressor rows for " +
                       std::to_string(P) + " parameters; give at least " +
                       std::to_string((P + nv - 1) / nv) + " (0: automatic)");
    // Peak memory: the samples (regressor and two energy matrices), and for the regressor's
    // elimination its triangular factor and residuals (rows x P each), F and Y (P x P, stored
    // sparse: up to half as much again as dense).
    const double rows = static_cast<double>(m) * nv;
    const double bytes = 8.0 * P * (3.0 * rows + 2.0 * me + 2.5 * P);
    if (bytes > options.numerical_budget) {
      char buf[320];
      std::snprintf(buf, sizeof buf,
                    "the numerical method would need about %.2g GiB for this %d-joint chain (%d "
                    "parameters, %.0f stacked regressor rows), over its budget of %.2g GiB; its "
                    "memory grows with the square and its time with the cube of the number of "
                    "joints",
                    bytes / 1073741824.0, n, P, rows, options.numerical_budget / 1073741824.0);
      throw ModelError(buf);
    }
    Samples s = sampleRegressors(model, layout, m, me, options.seed);
    // The energy sets: differences remove the constant, so keep one absolute sample row.
    ZL = sparse(s.wL);
    ZH = sparse(s.wH);
    ZE = sparse(s.W);
    bp.basis_rows = static_cast<int>(s.W.rows());
  }
  std::vector<int> kinds(P);
  for (int c = 0; c < P; ++c) {
    const int p = c % layout.perLink();
    kinds[c] = p < 6 ? 0 : (p < 9 ? 1 : (p == 9 ? 2 : 3 + (p - 10)));
  }
  // The projection method's Lagrangian is measured against the rows that reach the torques: its
  // constant potential (gravity times the heights) is no scale of what the torques resolve.
  // The scale of the whole robot is for the projection method's equations of motion, whose
  // rows, one per basis function, the torques mix (a potential row that is all small is no
  // measure of its entries). The recursive method's rows are directions, each normalised, and
  // each of the numerical method's is a whole torque at a state, which its entries are measured
  // against already. The Lagrangian and total energy are checked against the energies, whose
  // constant potential (gravity times the heights) is of another size than the torques: their
  // rows are measured as they are.
  bp.lagrangian = makeSet(echelon(ZL, order, tol, kinds, sizes, -1.0), bp.classical_names);
  if (options.method != BaseMethod::Numerical) {
    // The total-energy coordinates are the Lagrangian's with the potential rows negated: a
    // diagonal +-1 row scaling, which leaves every pivot, residual and Y exactly as they are
    // (recursive: the same row space, as the constant's sign does not change it).
    bp.energy = bp.lagrangian;
  } else {
    bp.energy = makeSet(echelon(ZH, order, tol, kinds, sizes, -1.0), bp.classical_names);
  }
  bp.eom = makeSet(
      echelon(ZE, order, tol, kinds, sizes, options.method == BaseMethod::Projection ? 0.0 : -1.0),
      bp.classical_names);
  if (options.method == BaseMethod::Recursive) {
    if (expand) {
      // The expansion's rows are independent, the real links' columns of them need not be: the
      // counts at the neighbouring tolerances are the echelon form's ranks of those columns of
      // the recursion's rows at those tolerances.
      const auto rank = [&](double t) {
        const Eigen::SparseMatrix<double> Z = recursiveCoordinates(
            recursiveIdentifiable(kernel, layout, t).rows * real, units, sizes);
        std::vector<int> pivots = echelon(Z, order, tol, kinds, sizes, -1.0).pivots;
        return std::make_pair(static_cast<long>(pivots.size()), std::move(pivots));
      };
      foldRecursiveMargins(tol, space, bp.eom.size(), rank, order, bp);
    } else {
      foldRecursiveMargins(
          tol, space, ZE.rows(),
          [&](double t) {
            const IdentifiableSpace at = recursiveIdentifiable(exact_model, layout, t);
            const auto rows = static_cast<long>(at.rows.rows());
            const Eigen::SparseMatrix<double> Z = recursiveCoordinates(at.rows, units, sizes);
            return std::make_pair(rows, echelon(Z, order, tol, kinds, sizes, -1.0).pivots);
          },
          order, bp);
    }
  }
  {
    Model copy = model;
    bp.snappable = snapRightAngles(copy, 1e-3);
  }
  checkRegrouping(model, layout, sizes, bp);
  refuseInconsistent(bp, tol);
  bp.lagrangian_equals_energy = bp.lagrangian.decision.pivots == bp.energy.decision.pivots;
  bp.lagrangian_equals_eom = bp.lagrangian.decision.pivots == bp.eom.decision.pivots;
  bp.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return bp;
}

// The joint block of `layout` (torque offsets) joined to the link sets `bp`. An offset's column
// is e_k in every state; a combination of link columns can be too: a vertical prismatic joint's
// mass column is m (ddq + g), its rotor inertia's Ia ddq, so M - Ia is the constant m g. Each
// offset stays a base parameter (after all link ones), and a link base column that is a
// combination of the offsets and the link columns after it in priority regroups into them (the
// mass above: Ia + M, Off_k + g M, the offset taking the weight), decided on sampled regressors:
// a column's residual after the offsets and those columns, relative to its size, at most the
// rank tolerance. The Lagrangian and the total energy do not contain offsets (their Y has zero
// columns there).
void joinJointBlock(const Model& model, ParameterLayout layout, const BaseOptions& options,
                    BaseParameters& bp) {
  const int n = model.nq(), P = layout.size(n), first = layout.offsetIndex(n, 0);
  const ParameterLayout links = layout.links();
  bp.layout = layout;
  bp.classical_names = model.parameterNames(layout);
  for (BaseSet* set : {&bp.lagrangian, &bp.energy, &bp.eom})
    set->decision.Y.conservativeResize(set->size(), P);
  RankDecision d = bp.eom.decision;
  const int nb = d.rank();
  // Sampled base regressor of the link set, n rows per state, and the offsets' columns.
  const long m = std::max(20, 3 * (nb + n) / std::max(1, n) + 20), rows = m * n;
  const double bytes = 8.0 * rows * (3.0 * (nb + n));
  if (bytes > options.numerical_budget)
    throw ModelError("torque offsets: comparing them with the " + std::to_string(nb) +
                     " link base parameters would need about " +
                     shortest(std::round(bytes / 1073741824.0 * 10) / 10) +
                     " GiB, over the numerical method's budget");
  Eigen::MatrixXd A(rows, n + nb);  // [offsets | link base columns]
  {
    Data data(model);
    std::mt19937 rng(options.seed);
    const StateScale scale(model);
    Eigen::VectorXd q(n), dq(n), ddq(n);
    Eigen::MatrixXd W(n, links.size(n)), Wf;
    A.leftCols(n).setZero();
    for (long s = 0; s < m; ++s) {
      randomState(model, rng, q, dq, ddq, scale);
      // at rest every fourth state: friction that is constant while a joint moves (Fa |sign v|)
      // is not constant then
      if (s % 4 == 0) dq.setZero();
      sampledRegressor(model, data, links, q, dq, ddq, scale, W, Wf);
      for (int k = 0; k < n; ++k) A(s * n + k, k) = 1.0;
      for (int b = 0; b < nb; ++b) A.block(s * n, n + b, n, 1) = W.col(d.pivots[b]);
    }
  }
  // Gram-Schmidt (twice) in priority order: the offsets, then the link base columns.
  Eigen::MatrixXd Q(rows, n + nb);
  for (int k = 0; k < n; ++k) Q.col(k) = A.col(k).normalized();
  int kept = n;
  std::vector<int> keep, drop;
  std::vector<double> residual;
  for (int b = nb - 1; b >= 0; --b) {  // last first: a dependent column is the earliest
    Eigen::VectorXd r = A.col(n + b);
    const double size = r.norm();
    for (int pass = 0; pass < 2; ++pass) r -= Q.leftCols(kept) * (Q.leftCols(kept).transpose() * r);
    const double rel = size > 0 ? r.norm() / size : 0.0;
    if (rel <= options.tolerance) {
      drop.push_back(b);
      residual.push_back(rel);
    } else {
      Q.col(kept++) = r / r.norm();
      keep.push_back(b);
    }
  }
  std::reverse(keep.begin(), keep.end());
  std::reverse(drop.begin(), drop.end());
  std::reverse(residual.begin(), residual.end());
  std::vector<Eigen::Triplet<double>> entries;
  if (drop.empty()) {
    entries.reserve(static_cast<size_t>(d.Y.nonZeros()) + n);
    for (int c = 0; c < d.Y.outerSize(); ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(d.Y, c); it; ++it)
        entries.emplace_back(it.row(), it.col(), it.value());
    for (int k = 0; k < n; ++k) {
      entries.emplace_back(nb + k, first + k, 1.0);
      d.pivots.push_back(first + k);
      d.pivot_size.push_back(1.0);
    }
  } else {
    // Each dropped column as a combination of the kept link columns and the offsets; its row
    // of Y folds into theirs.
    const int nk = static_cast<int>(keep.size());
    Eigen::MatrixXd K(rows, nk + n), D(rows, static_cast<long>(drop.size()));
    for (int i = 0; i < nk; ++i) K.col(i) = A.col(n + keep[i]);
    K.rightCols(n) = A.leftCols(n);
    for (size_t j = 0; j < drop.size(); ++j) D.col(static_cast<long>(j)) = A.col(n + drop[j]);
    Eigen::MatrixXd X = K.colPivHouseholderQr().solve(D);
    // the least-squares round-off on the columns a dropped one does not involve: exact zeros
    for (long j = 0; j < X.cols(); ++j)
      for (long i = 0; i < X.rows(); ++i)
        if (std::abs(X(i, j)) * K.col(i).norm() <= 1e-10 * D.col(j).norm()) X(i, j) = 0.0;
    const Eigen::MatrixXd Yd(d.Y);
    Eigen::MatrixXd Yn(nk + n, P);
    for (int i = 0; i < nk; ++i) Yn.row(i) = Yd.row(keep[i]);
    Yn.bottomRows(n).setZero();
    for (int k = 0; k < n; ++k) Yn(nk + k, first + k) = 1.0;
    for (size_t j = 0; j < drop.size(); ++j) Yn += X.col(static_cast<long>(j)) * Yd.row(drop[j]);
    for (int c = 0; c < P; ++c)
      for (int r = 0; r < nk + n; ++r)
        if (Yn(r, c) != 0.0) entries.emplace_back(r, c, Yn(r, c));
    std::vector<int> pivots;
    std::vector<double> sizes;
    for (int i : keep) {
      pivots.push_back(d.pivots[i]);
      sizes.push_back(d.pivot_size[i]);
    }
    for (size_t j = 0; j < drop.size(); ++j) {
      d.dependent.push_back(d.pivots[drop[j]]);
      d.residual.push_back(residual[j]);
    }
    for (int k = 0; k < n; ++k) {
      pivots.push_back(first + k);
      sizes.push_back(1.0);
    }
    d.pivots = pivots;
    d.pivot_size = sizes;
  }
  const int added = n - static_cast<int>(drop.size());
  d.Y.resize(static_cast<long>(d.pivots.size()), P);
  d.Y.setFromTriplets(entries.begin(), entries.end());
  if (d.rank_looser >= 0) d.rank_looser += added;
  if (d.rank_tighter >= 0) d.rank_tighter += added;
  bp.eom = makeSet(std::move(d), bp.classical_names);
}

}  // namespace

BaseParameters computeBaseParameters(const Model& model, const BaseOptions& options) {
  if (!options.layout.offset) return linkBaseParameters(model, options);
  if (!model.singleDof())
    throw ModelError("torque offsets are defined for revolute and prismatic joints only; model '" +
                     model.name + "' has multi-DOF joints");
  const auto start = std::chrono::steady_clock::now();
  BaseOptions links = options;
  links.layout = options.layout.links();
  BaseParameters bp = linkBaseParameters(model, links);
  joinJointBlock(model, options.layout, options, bp);
  bp.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return bp;
}

void baseRegressor(const Model& model, Data& data, const BaseParameters& base, const VecRef& q,
                   const VecRef& dq, const VecRef& ddq, MatOut W, MatOut Wb) noexcept {
  regressor(model, data, q, dq, ddq, base.layout, W);
  const auto& piv = base.eom.decision.pivots;
  for (size_t b = 0; b < piv.size(); ++b) Wb.col(static_cast<long>(b)) = W.col(piv[b]);
}

void baseEnergyRegressor(const Model& model, Data& data, const BaseParameters& base,
                         const VecRef& q, const VecRef& dq, VecOut wK, VecOut wP,
                         VecOut wb) noexcept {
  energyRegressors(model, data, q, dq, base.layout, wK, wP);
  const auto& piv = base.eom.decision.pivots;
  for (size_t b = 0; b < piv.size(); ++b) wb[static_cast<long>(b)] = wK[piv[b]] + wP[piv[b]];
}

std::vector<std::string> snapRightAngles(Model& model, double tolerance,
                                         std::vector<SnapChange>* changes) {
  std::vector<std::string> report;
  int joint = 0;
  auto record = [&](const char* frame, const char* component, double value, double snapped) {
    if (changes)
      changes->push_back({joint, model.joints[static_cast<size_t>(joint)].name, frame, component,
                          value, snapped, std::abs(value - snapped)});
  };
  auto snapAngle = [tolerance](double a, bool& changed) {
    const double k = std::round(a / (kPi / 2));
    const double s = k * (kPi / 2) + 0.0;  // + 0.0: a snap to zero is 0, never -0
    if (std::abs(a - s) <= tolerance && a != s) {
      changed = true;
      return s;
    }
    return a;
  };
  auto snapRotation = [&](Eigen::Isometry3d& T, const std::string& what, const char* frame) {
    const Eigen::Matrix3d R = T.linear();
    // Already exactly a signed permutation: nothing to do.
    bool exact = true;
    for (int i = 0; i < 9; ++i) {
      const double v = std::abs(R.data()[i]);
      if (v != 0.0 && v != 1.0) exact = false;
    }
    if (exact) return;
    const Eigen::Vector3d ypr = R.eulerAngles(2, 1, 0);
    bool changed = false;
    Eigen::Vector3d s;
    for (int i = 0; i < 3; ++i) s[i] = snapAngle(ypr[i], changed);
    bool all_right = true;
    for (int i = 0; i < 3; ++i)
      if (std::abs(s[i] / (kPi / 2) - std::round(s[i] / (kPi / 2))) > 1e-12) all_right = false;
    Eigen::Matrix3d Rs = (Eigen::AngleAxisd(s[0], Eigen::Vector3d::UnitZ()) *
                          Eigen::AngleAxisd(s[1], Eigen::Vector3d::UnitY()) *
                          Eigen::AngleAxisd(s[2], Eigen::Vector3d::UnitX()))
                             .toRotationMatrix();
    if (all_right) {
      for (int i = 0; i < 9; ++i) Rs.data()[i] = std::round(Rs.data()[i]);
      changed = changed || Rs != R;
    }
    if (!changed) return;
    T.linear() = Rs;
    static const char* const kAngles[] = {"yaw", "pitch", "roll"};
    for (int i = 0; i < 3; ++i)
      if (s[i] != ypr[i]) record(frame, kAngles[i], ypr[i], s[i]);
    report.push_back(
        what + ": rotation (yaw, pitch, roll) = (" + shortest(ypr[0]) + ", " + shortest(ypr[1]) +
        ", " + shortest(ypr[2]) + ") rad -> (" + shortest(s[0]) + ", " + shortest(s[1]) + ", " +
        shortest(s[2]) + ")" +
        (all_right ? ", all multiples of pi/2" : ", angles near multiples of pi/2 rounded"));
  };
  for (; joint < static_cast<int>(model.joints.size()); ++joint) {
    Joint& j = model.joints[static_cast<size_t>(joint)];
    snapRotation(j.pre, "joint '" + j.name + "' origin", "origin");
    snapRotation(j.post, "joint '" + j.name + "' link frame", "link frame");
    Eigen::Vector3d a = j.axis;
    bool changed = false;
    static const char* const kAxes[] = {"x", "y", "z"};
    for (int i = 0; i < 3; ++i) {
      if (a[i] != 0.0 && std::abs(a[i]) <= tolerance) {
        record("axis", kAxes[i], a[i], 0.0);
        a[i] = 0.0;
        changed = true;
      }
    }
    if (changed) {
      const Eigen::Vector3d old = j.axis;
      j.axis = a.normalized();
      for (int i = 0; i < 3; ++i)
        if (std::abs(std::abs(j.axis[i]) - 1.0) < 1e-15) j.axis[i] = j.axis[i] > 0 ? 1.0 : -1.0;
      report.push_back("joint '" + j.name + "' axis (" + shortest(old[0]) + ", " +
                       shortest(old[1]) + ", " + shortest(old[2]) + ") snapped to (" +
                       shortest(j.axis[0]) + ", " + shortest(j.axis[1]) + ", " +
                       shortest(j.axis[2]) + ")");
    }
  }
  return report;
}

}  // namespace mindyn
