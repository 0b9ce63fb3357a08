#include "mindyn/projection.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <bitset>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <map>
#include <sstream>
#include <type_traits>

#include "mindyn/spatial.hpp"

namespace mindyn {

namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Row4d = Eigen::Matrix<double, 1, 4>;

constexpr int kL0Bits = 10;
constexpr int kJointBits = 3;
constexpr int kMaxJoints = (64 - kL0Bits) / kJointBits;  // 18
constexpr int kMaxTreeJoints = 44;                       // n(n + 1)/2 pairs in kL0Bits
static_assert(kProjectionMaxParameters % 64 == 0 && kProjectionMaxParameters >= 15 * kMaxTreeJoints,
              "the row reduction's masks hold every column of a tree of the most joints");

inline int pairIndex(int i, int j) {  // 1-based, j <= i
  return i * (i - 1) / 2 + j;
}
// A free-flyer joint whose parent is the world: the projection method takes it natively (its
// stage is formed from the base twist and the gravity direction in base axes, below).
inline bool isFloatingRoot(const Model& model, int k) {
  return model.joints[static_cast<std::size_t>(k)].type == JointType::FreeFlyer &&
         model.parent(k) < 0;
}
bool hasFloatingRoot(const Model& model) {
  for (int k = 0; k < model.nq(); ++k)
    if (isFloatingRoot(model, k)) return true;
  return false;
}
// Every joint is revolute, prismatic or a floating root: the recursion takes the model as it is.
bool recursionTakes(const Model& model) {
  for (int k = 0; k < model.nq(); ++k)
    if (!model.joints[static_cast<std::size_t>(k)].singleDof() && !isFloatingRoot(model, k))
      return false;
  return true;
}
// 1-based index of each joint's first velocity (Pinocchio's v): the velocities the basis
// functions' products dq_i dq_j number.
std::vector<int> velocityIndex(const Model& model) {
  std::vector<int> v(static_cast<std::size_t>(model.nq()));
  int i = 1;
  for (int k = 0; k < model.nq(); ++k) {
    v[static_cast<std::size_t>(k)] = i;
    i += model.joints[static_cast<std::size_t>(k)].nv();
  }
  return v;
}
// The 1-based velocity index of component a (0..5, angular first as mindyn's twists) of a
// free-flyer whose first velocity is v0: Pinocchio's v is linear first.
inline int floatingVelocity(int v0, int a) { return v0 + (a < 3 ? a + 3 : a - 3); }

inline std::uint64_t withJoint(std::uint64_t key, int joint, int l) {  // joint 0-based, l 1-based
  return key | (static_cast<std::uint64_t>(l - 1) << (kL0Bits + kJointBits * joint));
}
// A tree's keys give each joint's factor at its position on its root path (its number of
// ancestors) and keep above the factors the deepest joint they involve, plus one (0: none),
// which names the path: two basis functions of different paths differ there. A serial chain's
// keys keep no deepest joint (a joint's position is its index).
struct KeyLayout {
  std::vector<int> shift;  // bit position of each joint's factor
  int end_shift = 64;      // where a tree's key keeps its deepest joint
  std::uint64_t end_mask = 0;
  int longest = 0;   // joints on the longest root path
  bool fits = true;  // the keys fit in 64 bits
};
KeyLayout keyLayout(const Model& model) {
  const int n = model.nq();
  KeyLayout kl;
  kl.shift.resize(static_cast<std::size_t>(n));
  std::vector<int> pos(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    const int p = model.parent(k);
    pos[static_cast<std::size_t>(k)] = p < 0 ? 0 : pos[static_cast<std::size_t>(p)] + 1;
    kl.shift[static_cast<std::size_t>(k)] = kL0Bits + kJointBits * pos[static_cast<std::size_t>(k)];
    kl.longest = std::max(kl.longest, pos[static_cast<std::size_t>(k)] + 1);
  }
  if (model.isSerial() && !hasFloatingRoot(model)) {  // a floating root: a tree's keys
    kl.fits = n <= kMaxJoints;
    return kl;
  }
  int bits = 0;
  while ((n + 1) >> bits) ++bits;  // 0 .. n
  kl.end_shift = kL0Bits + kJointBits * kl.longest;
  kl.fits = kl.end_shift + bits <= 64;
  if (kl.fits) kl.end_mask = ((std::uint64_t{1} << bits) - 1) << kl.end_shift;
  return kl;
}
inline std::uint64_t withL0(std::uint64_t key, int l0) {
  return key | static_cast<std::uint64_t>(l0);
}

// Twist transformation (angular; linear) of a rigid transform.
Matrix6d adjoint(const Eigen::Isometry3d& T) {
  Matrix6d A = Matrix6d::Zero();
  A.topLeftCorner<3, 3>() = T.linear();
  A.bottomRightCorner<3, 3>() = T.linear();
  A.bottomLeftCorner<3, 3>() = skew(T.translation()) * T.linear();
  return A;
}

// Rotation taking z to u, exact for the axis-aligned cases.
Eigen::Matrix3d alignZ(const Eigen::Vector3d& u) {
  if (u == Eigen::Vector3d::UnitZ()) return Eigen::Matrix3d::Identity();
  if (u == -Eigen::Vector3d::UnitZ()) return Eigen::Vector3d(1, -1, -1).asDiagonal();
  if (u == Eigen::Vector3d::UnitX()) {
    Eigen::Matrix3d C;
    C << 0, 0, 1, 1, 0, 0, 0, 1, 0;
    return C;
  }
  if (u == Eigen::Vector3d::UnitY()) {
    Eigen::Matrix3d C;
    C << 0, 1, 0, 0, 0, 1, 1, 0, 0;
    return C;
  }
  if (u == -Eigen::Vector3d::UnitX()) {
    Eigen::Matrix3d C;
    C << 0, 0, -1, -1, 0, 0, 0, 1, 0;
    return C;
  }
  if (u == -Eigen::Vector3d::UnitY()) {
    Eigen::Matrix3d C;
    C << 0, -1, 0, 0, 0, -1, 1, 0, 0;
    return C;
  }
  return Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), u).toRotationMatrix();
}

template <class M>
double maxAbs(const M& m) {
  return m.cwiseAbs().maxCoeff();
}

// Zeroes entries below tol; returns the largest remaining |entry| (0: nothing left).
template <class M>
double pruneMax(M& m, double tol) {
  double big = 0.0;
  for (int i = 0; i < static_cast<int>(m.size()); ++i) {
    const double a = std::abs(m.data()[i]);
    if (a <= tol)
      m.data()[i] = 0.0;
    else if (a > big)
      big = a;
  }
  return big;
}

// Zeroes entries below tol; true if something is left.
template <class M>
bool prune(M& m, double tol) {
  bool any = false;
  for (int i = 0; i < static_cast<int>(m.size()); ++i) {
    if (std::abs(m.data()[i]) <= tol)
      m.data()[i] = 0.0;
    else
      any = true;
  }
  return any;
}

// Symmetric 6x6 matrices stored as their 21 upper entries.
using Sym6 = std::array<double, 21>;
struct SymIndex {
  int idx[6][6];
  int first[21], second[21];  // (i, j), i <= j, of each packed entry
  constexpr SymIndex() : idx(), first(), second() {
    int k = 0;
    for (int i = 0; i < 6; ++i)
      for (int j = i; j < 6; ++j) {
        first[k] = i;
        second[k] = j;
        idx[i][j] = idx[j][i] = k++;
      }
  }
};
constexpr SymIndex kSym;

inline void toFull(const Sym6& s, Matrix6d& m) {
  for (int i = 0; i < 6; ++i)
    for (int j = i; j < 6; ++j) m(i, j) = m(j, i) = s[kSym.idx[i][j]];
}
inline Sym6 toSym(const Matrix6d& m) {
  Sym6 s;
  for (int i = 0; i < 6; ++i)
    for (int j = i; j < 6; ++j) s[kSym.idx[i][j]] = m(i, j);
  return s;
}

// The entries of a packed symmetric matrix that may be non-zero, ascending.
struct Pattern {
  int count = 0;
  int idx[21];
};

// A constant 6x6 map kept as its non-zero entries (geometry is often axis-aligned), by rows
// and by columns.
struct Sparse6 {
  int count = 0;
  int row[36], col[36];
  double val[36];
  int colStart[7];  // column j: rows colRow[colStart[j] .. colStart[j + 1] - 1], ascending
  int colRow[36];
  double colVal[36];
  explicit Sparse6(const Matrix6d& m) {
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j)
        if (m(i, j) != 0.0) {
          row[count] = i;
          col[count] = j;
          val[count] = m(i, j);
          ++count;
        }
    int c = 0;
    for (int j = 0; j < 6; ++j) {
      colStart[j] = c;
      for (int i = 0; i < 6; ++i)
        if (m(i, j) != 0.0) {
          colRow[c] = i;
          colVal[c] = m(i, j);
          ++c;
        }
    }
    colStart[6] = c;
  }
  // C Q C^T for a packed symmetric Q whose non-zero entries lie in `where`; only the upper
  // triangle of the product is formed.
  void congruence(const Sym6& Q, const Pattern& where, Sym6& out) const {
    // T = C Q, entry by entry of Q; every T(r, j) sums C(r, a) Q(a, j) by ascending a.
    double T[6][6] = {};
    for (int w = 0; w < where.count; ++w) {
      const int q = where.idx[w];
      const double v = Q[q];
      if (v == 0.0) continue;
      const int a = kSym.first[q], b = kSym.second[q];
      for (int e = colStart[a]; e < colStart[a + 1]; ++e) T[colRow[e]][b] += colVal[e] * v;
      if (a != b)
        for (int e = colStart[b]; e < colStart[b + 1]; ++e) T[colRow[e]][a] += colVal[e] * v;
    }
    out.fill(0.0);
    for (int e = 0; e < count; ++e)
      for (int i = 0; i <= row[e]; ++i) out[kSym.idx[i][row[e]]] += val[e] * T[i][col[e]];
  }
  void apply(const Vector6d& x, Vector6d& out) const {
    out.setZero();
    for (int e = 0; e < count; ++e) out[row[e]] += val[e] * x[col[e]];
  }
};

// The ten forms 1/2 tr(E_p Q), p = 0..9, for constant symmetric E_p and a packed symmetric Q.
// For each kind of term, only the entries of Q it may hold and the forms see are visited, in
// ascending order: each value sums its terms in the order of the entries of Q. Where few of the
// weights of those entries are non-zero (axis-aligned link frames), only those are visited;
// otherwise every entry with all ten weights, zeros included (no data-dependent branches).
class TraceForms {
 public:
  TraceForms(const std::array<Matrix6d, 10>& E, const Pattern* kinds, int count) {
    for (int i = 0; i < 6; ++i)
      for (int j = i; j < 6; ++j) {
        const int q = kSym.idx[i][j];
        for (int p = 0; p < 10; ++p)
          w_[q][p] = i == j ? 0.5 * E[p](i, i) : 0.5 * (E[p](i, j) + E[p](j, i));
      }
    kinds_.resize(count);
    for (int k = 0; k < count; ++k) {
      Kind& kind = kinds_[k];
      kind.first = static_cast<int>(sparse_.size());
      for (int i = 0; i < kinds[k].count; ++i) {
        const int q = kinds[k].idx[i];
        bool seen = false;
        for (int p = 0; p < 10; ++p)
          if (w_[q][p] != 0.0) {
            sparse_.push_back(
                {static_cast<std::uint8_t>(q), static_cast<std::uint8_t>(p), w_[q][p]});
            kind.touched |= 1u << p;
            seen = true;
          }
        if (seen) kind.dense.idx[kind.dense.count++] = q;
      }
      kind.last = static_cast<int>(sparse_.size());
      kind.use_sparse = kind.last - kind.first <= 2 * kind.dense.count;
    }
  }
  // v[p] for the forms a term of kind `kind` can reach: the bits of the result (the other
  // values are zero).
  unsigned operator()(const Sym6& Q, int kind, double v[10]) const {
    const Kind& k = kinds_[kind];
    if (k.use_sparse) {
      for (int p = 0; p < 10; ++p) v[p] = 0.0;
      for (int e = k.first; e < k.last; ++e) v[sparse_[e].p] += sparse_[e].w * Q[sparse_[e].q];
    } else {
      double acc[10] = {};
      for (int i = 0; i < k.dense.count; ++i) {
        const int q = k.dense.idx[i];
        for (int p = 0; p < 10; ++p) acc[p] += w_[q][p] * Q[q];
      }
      for (int p = 0; p < 10; ++p) v[p] = acc[p];
    }
    return k.touched;
  }

 private:
  struct Weight {
    std::uint8_t q, p;
    double w;
  };
  struct Kind {
    Pattern dense;            // the entries with a non-zero weight
    int first = 0, last = 0;  // their non-zero weights: sparse_[first .. last - 1]
    unsigned touched = 0;
    bool use_sparse = false;
  };
  double w_[21][10];
  std::vector<Weight> sparse_;
  std::vector<Kind> kinds_;
};

// R B R^T for R = blockdiag(Rz(-q), Rz(-q)), B symmetric, split over 1, cos q, sin q, cos 2q,
// sin 2q. Indices 2 and 5 lie on the axis; (0, 1) and (3, 4) rotate as (x, y) -> (c x + s y,
// -s x + c y). Entries up to `tol` are set to zero; big[l] receives the largest |entry| of part l.
void splitRotation(const Sym6& Bp, double tol, Sym6 parts[5], double big[5]) {
  std::memset(parts, 0, 5 * sizeof(Sym6));
  for (int l = 0; l < 5; ++l) big[l] = 0.0;
  const auto& I = kSym.idx;
  auto B = [&](int i, int j) { return Bp[I[i][j]]; };
  auto put = [&](int l, int i, int j, double v) {
    const double a = std::abs(v);
    if (a <= tol) return;
    parts[l][I[i][j]] = v;
    big[l] = std::max(big[l], a);
  };
  static constexpr int ax[2] = {2, 5};
  static constexpr int px[2] = {0, 3};
  put(0, 2, 2, B(2, 2));
  put(0, 2, 5, B(2, 5));
  put(0, 5, 5, B(5, 5));
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) {
      const int z = ax[a], x = px[b], y = px[b] + 1;
      // D(z, x') = c B(z,x) + s B(z,y);  D(z, y') = -s B(z,x) + c B(z,y)
      put(1, z, x, B(z, x));
      put(2, z, x, B(z, y));
      put(1, z, y, B(z, y));
      put(2, z, y, -B(z, x));
    }
  for (int a = 0; a < 2; ++a)
    for (int b = a; b < 2; ++b) {
      const int x1 = px[a], y1 = px[a] + 1, x2 = px[b], y2 = px[b] + 1;
      const double xx = B(x1, x2), xy = B(x1, y2), yx = B(y1, x2), yy = B(y1, y2);
      put(0, x1, x2, 0.5 * (xx + yy));
      put(3, x1, x2, 0.5 * (xx - yy));
      put(4, x1, x2, 0.5 * (xy + yx));
      put(0, x1, y2, 0.5 * (xy - yx));
      put(3, x1, y2, 0.5 * (xy + yx));
      put(4, x1, y2, 0.5 * (yy - xx));
      put(0, y1, y2, 0.5 * (xx + yy));
      put(3, y1, y2, -0.5 * (xx - yy));
      put(4, y1, y2, -0.5 * (xy + yx));
      if (a != b) {  // (y1, x2) lies in the upper triangle too
        put(0, y1, x2, 0.5 * (yx - xy));
        put(3, y1, x2, 0.5 * (xy + yx));
        put(4, y1, x2, 0.5 * (yy - xx));
      }
    }
}

// What a kinetic term may hold: one of the five parts of a rotation split, x S^T + S x^T or
// S S^T for the joint's S = e_2 (revolute) or e_5 (prismatic), or anything.
enum TermKind : std::uint8_t { kCross2 = 5, kCross5, kDiag2, kDiag5, kAny, kKinds };

const std::array<Pattern, kKinds>& patterns() {
  static const std::array<Pattern, kKinds> table = [] {
    std::array<bool[21], kKinds> nonzero{};
    Sym6 generic;  // distinct positive entries: no sum or difference of two of them cancels
    for (int q = 0; q < 21; ++q) generic[q] = std::sqrt(q + 2.0);
    Sym6 parts[5];
    double big[5];
    splitRotation(generic, 0.0, parts, big);
    for (int l = 0; l < 5; ++l)
      for (int q = 0; q < 21; ++q) nonzero[l][q] = parts[l][q] != 0.0;
    for (int i = 0; i < 6; ++i) {
      nonzero[kCross2][kSym.idx[i][2]] = true;
      nonzero[kCross5][kSym.idx[i][5]] = true;
    }
    nonzero[kDiag2][kSym.idx[2][2]] = true;
    nonzero[kDiag5][kSym.idx[5][5]] = true;
    for (bool& b : nonzero[kAny]) b = true;
    std::array<Pattern, kKinds> t;
    for (int k = 0; k < kKinds; ++k)
      for (int q = 0; q < 21; ++q)
        if (nonzero[k][q]) t[k].idx[t[k].count++] = q;
    return t;
  }();
  return table;
}

// The parts of y through a joint: times 1, cos q, sin q for a revolute joint (part(a), a < 3),
// times 1, q for a prismatic one (y, part(3)). Returns their number.
template <class V, class Part>
int jointParts(bool revolute, const V& y, V parts[3], Part part) {
  if (revolute) {
    for (int a = 0; a < 3; ++a) parts[a] = part(a);
    return 3;
  }
  parts[0] = y;
  parts[1] = part(3);
  return 2;
}

// Terms of the recursion. `row` is the row of Z of the term's basis function, -1 while it has
// none: a term carried through a joint by its constant factor keeps its key, hence its row;
// the other terms have keys that no earlier term had.
struct QTerm {
  std::uint64_t key;
  int row;
  std::uint8_t kind;  // TermKind or the part of a rotation split (0..4)
  double scale;       // largest |entry|
  Sym6 Q;
};
struct VTerm {
  int i;              // 1-based velocity (Pinocchio's v) that multiplies this term
  std::uint64_t key;  // joint indices only
  Vector6d x;
};
struct RTerm {
  std::uint64_t key;
  int row;
  Row4d r;
};
using Entry = InfluenceCoordinates::Entry;

// The terms after a joint, from which its children start. A term of a stage that several
// children start from may hold, instead of a row, a shared slot -2 - s: the row its basis
// function gets in whichever branch first gives it a coordinate.
struct Stage {
  std::vector<QTerm> Q;
  std::vector<VTerm> V;
  std::vector<RTerm> R;
};

// Number of child joints of the base (entry 0) and of each joint k (entry k + 1).
std::vector<int> childCounts(const Model& model) {
  std::vector<int> c(static_cast<std::size_t>(model.nq()) + 1, 0);
  for (int k = 0; k < model.nq(); ++k) ++c[static_cast<std::size_t>(model.parent(k) + 1)];
  return c;
}

// Relative size below which a coefficient is rounding noise of exactly-zero structure.
constexpr double kNoise = 1e-13;

// Joint frames aligned so that every joint moves about / along its z axis.
void alignedFrames(const Model& model, std::vector<Eigen::Isometry3d>& pre,
                   std::vector<Eigen::Isometry3d>& post) {
  const int n = model.nq();
  pre.resize(n);
  post.resize(n);
  for (int k = 0; k < n; ++k) {
    const Joint& j = model.joints[k];
    Eigen::Isometry3d C = Eigen::Isometry3d::Identity();
    if (j.singleDof()) C.linear() = alignZ(j.axis);  // a free-flyer's twist: in its moved frame
    pre[k] = j.pre * C;
    post[k] = C.inverse() * j.post;
  }
}

// Per-link kinetic parameter forms E'_p (10 per link) in the aligned joint frame, `post` the
// transform from it to the link frame.
std::array<Matrix6d, 10> linkForms(const Eigen::Isometry3d& post) {
  std::array<Matrix6d, 10> E;
  for (auto& e : E) e.setZero();
  E[0](0, 0) = 1;
  E[1](0, 1) = E[1](1, 0) = 1;
  E[2](0, 2) = E[2](2, 0) = 1;
  E[3](1, 1) = 1;
  E[4](1, 2) = E[4](2, 1) = 1;
  E[5](2, 2) = 1;
  for (int a = 0; a < 3; ++a) {
    const Eigen::Matrix3d S = skew(Eigen::Vector3d::Unit(a));
    E[6 + a].topRightCorner<3, 3>() = S;
    E[6 + a].bottomLeftCorner<3, 3>() = S.transpose();
  }
  E[9].bottomRightCorner<3, 3>().setIdentity();
  const Matrix6d A = adjoint(post.inverse());
  if (A != Matrix6d::Identity())  // the link frame is not the joint frame
    for (auto& e : E) {
      Matrix6d f = Matrix6d::Zero();  // A^T e A over the few non-zero entries of e
      for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j)
          if (e(i, j) != 0.0) f.noalias() += e(i, j) * A.row(i).transpose() * A.row(j);
      e = f;
      prune(e, kNoise * maxAbs(e));
    }
  return E;
}

// The twist map of the fixed transform before a joint, rounding noise of exact zeros removed.
Matrix6d jointMap(const Eigen::Isometry3d& T) {
  Matrix6d Cd = adjoint(T.inverse());
  prune(Cd, 1e-16 * std::max(1.0, maxAbs(Cd)));
  return Cd;
}

// --- Cost of the recursion, on sparsity patterns ---------------------------------------------
// A term is represented by the set of its entries that may be non-zero (bit masks); terms of
// equal pattern and kind behave alike, so only their number is carried.
using Mask = std::uint32_t;

Sym6 genericOn(Mask mask) {  // distinct positive values on the mask: no sum or difference cancels
  Sym6 g{};
  for (int q = 0; q < 21; ++q)
    if (mask >> q & 1u) g[q] = std::sqrt(q + 2.0);
  return g;
}
Mask maskOf(const Sym6& s) {
  Mask m = 0;
  for (int q = 0; q < 21; ++q)
    if (s[q] != 0.0) m |= 1u << q;
  return m;
}
// Pattern of C Q C^T.
Mask congruencePattern(const bool C[6][6], Mask q) {
  bool T[6][6] = {};  // C Q
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b)
      if (q >> kSym.idx[a][b] & 1u)
        for (int r = 0; r < 6; ++r)
          if (C[r][a]) T[r][b] = true;
  Mask out = 0;
  for (int i = 0; i < 6; ++i)
    for (int j = i; j < 6; ++j)
      for (int b = 0; b < 6 && !(out >> kSym.idx[i][j] & 1u); ++b)
        if (T[i][b] && C[j][b]) out |= 1u << kSym.idx[i][j];
  return out;
}
template <int N>
unsigned applyPattern(const Eigen::Matrix<double, N, N>& M, unsigned x, bool transpose) {
  unsigned out = 0;
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j)
      if ((transpose ? M(j, i) : M(i, j)) != 0.0 && (x >> j & 1u)) out |= 1u << i;
  return out;
}

std::string overBudget(const Model& model, const ProjectionCost& c, double budget) {
  auto gib = [](double b) {
    std::ostringstream o;
    o << std::setprecision(b < 10 * 1073741824.0 ? 2 : 3) << b / 1073741824.0 << " GiB";
    return o.str();
  };
  std::ostringstream o;
  o << std::setprecision(2) << "the projection method would need up to " << gib(c.bytes)
    << " (estimated before computing: up to " << c.rows << " basis rows and " << c.terms
    << " terms for this " << model.nq() << (model.isSerial() ? "-joint chain" : "-joint tree")
    << "), over its budget of " << gib(budget)
    << " (the basis grows geometrically along runs of parallel or general joint axes)";
  return o.str();
}

}  // namespace

std::uint64_t packBasis(int l0, const std::vector<int>& l) {
  if (static_cast<int>(l.size()) > kMaxJoints)
    throw ModelError("basis index: at most " + std::to_string(kMaxJoints) + " joints");
  std::uint64_t key = static_cast<std::uint64_t>(l0);
  for (size_t j = 0; j < l.size(); ++j) key = withJoint(key, static_cast<int>(j), l[j]);
  return key;
}

BasisFunction unpackBasis(std::uint64_t key, int n) {
  BasisFunction b;
  b.l0 = static_cast<int>(key & ((1u << kL0Bits) - 1));
  b.l.resize(n);
  for (int j = 0; j < n; ++j)
    b.l[j] = static_cast<int>((key >> (kL0Bits + kJointBits * j)) & 7u) + 1;
  return b;
}

std::string BasisFunction::toString(const Model& model) const {
  std::string s;
  auto add = [&s](const std::string& f) { s += (s.empty() ? "" : "*") + f; };
  // The name of 1-based velocity i: dqK of joint K, vxK .. wzK of a floating root K.
  const std::vector<int> first = velocityIndex(model);
  auto velocity = [&](int i) {
    int k = 0;
    while (k + 1 < model.nq() && first[static_cast<std::size_t>(k + 1)] <= i) ++k;
    const std::string K = std::to_string(k + 1);
    if (!model.joints[static_cast<std::size_t>(k)].singleDof()) {
      static const char* c[] = {"vx", "vy", "vz", "wx", "wy", "wz"};
      return c[i - first[static_cast<std::size_t>(k)]] + K;
    }
    return "dq" + K;
  };
  if (l0 > 0) {
    const int i = static_cast<int>(std::floor((1 + std::sqrt(8.0 * l0 - 7)) / 2));
    const int j = l0 - i * (i - 1) / 2;
    if (i == j)
      add("0.5*" + velocity(i) + "^2");
    else
      add(velocity(j) + "*" + velocity(i));
  }
  for (size_t k = 0; k < l.size(); ++k) {
    const std::string q = "q" + std::to_string(k + 1);
    if (model.joints[k].type == JointType::FreeFlyer) {
      // ux, uy, uz: the direction of gravity in the floating body's moved frame, R^T g / |g|; h:
      // the position of its origin along gravity, g . p / |g|
      static const char* f[] = {"", "ux", "uy", "uz", "h"};
      if (l[k] > 1) add(f[l[k] - 1] + std::to_string(k + 1));
    } else if (model.joints[k].type == JointType::Revolute) {
      static const char* f[] = {"", "cos(%)", "sin(%)", "cos(2%)", "sin(2%)"};
      if (l[k] > 1) {
        std::string t = f[l[k] - 1];
        t.replace(t.find('%'), 1, q);
        add(t);
      }
    } else {
      if (l[k] == 2) add(q);
      if (l[k] == 3) add(q + "^2");
    }
  }
  return s.empty() ? "1" : s;
}

int InfluenceCoordinates::constantRow() const {
  for (size_t r = 0; r < keys.size(); ++r)
    if (keys[r] == 0) return static_cast<int>(r);
  return -1;
}

BasisFunction InfluenceCoordinates::basis(int row) const {
  const std::uint64_t key = keys.at(row);
  if (parents.empty()) return unpackBasis(key, n);
  // A tree: the factors of the root path of the deepest joint, by position on the path.
  BasisFunction b;
  b.l0 = static_cast<int>(key & ((1u << kL0Bits) - 1));
  b.l.assign(static_cast<std::size_t>(n), 1);
  std::vector<int> path;
  for (int j = static_cast<int>(key >> end_shift) - 1; j >= 0; j = parents[static_cast<size_t>(j)])
    path.push_back(j);
  const int len = static_cast<int>(path.size());
  for (int i = 0; i < len; ++i)
    b.l[static_cast<std::size_t>(path[static_cast<std::size_t>(len - 1 - i)])] =
        static_cast<int>((key >> (kL0Bits + kJointBits * i)) & 7u) + 1;
  return b;
}

int InfluenceCoordinates::depth(int row) const {
  const std::uint64_t key = keys.at(row);
  if (!parents.empty()) return static_cast<int>(key >> end_shift);  // a tree keeps it
  // l0 = J(i, j) = i(i-1)/2 + j, 1 <= j <= i, involves joint i at most
  static const std::array<std::uint8_t, 1u << kL0Bits> pairDepth = [] {
    std::array<std::uint8_t, 1u << kL0Bits> d{};
    int i = 0;
    for (int l0 = 1; l0 < static_cast<int>(d.size()); ++l0) {
      if (i * (i + 1) / 2 < l0) ++i;
      d[l0] = static_cast<std::uint8_t>(i);
    }
    return d;
  }();
  const int d = pairDepth[key & ((1u << kL0Bits) - 1)];
  // the last joint with a non-constant factor
  const std::uint64_t joints = key >> kL0Bits;
#if defined(__GNUC__) || defined(__clang__)
  const int last = joints != 0 ? (63 - __builtin_clzll(joints)) / kJointBits + 1 : 0;
#else
  int last = 0;
  for (std::uint64_t j = joints; j != 0; j >>= kJointBits) ++last;
#endif
  return std::max(d, last);
}

Eigen::MatrixXd InfluenceCoordinates::dense() const {
  Eigen::MatrixXd Z = Eigen::MatrixXd::Zero(rows(), cols());
  for (const auto& e : entries) Z(e.row, e.col) += e.value;
  return Z;
}

ProjectionCost projectionCost(const Model& model, ParameterLayout layout) {
  model.validate();
  if (!recursionTakes(model))  // what the recursion runs on (see projectionRefusal)
    return projectionCost(expandToSingleDof(model, true).model, layout);
  const int n = model.nq();
  std::vector<Eigen::Isometry3d> pre, post;
  alignedFrames(model, pre, post);
  const auto& kinds = patterns();
  Matrix6d R6[3], N6 = Matrix6d::Zero();
  for (auto& r : R6) r.setZero();
  R6[0](2, 2) = R6[0](5, 5) = 1;
  for (int i : {0, 1, 3, 4}) R6[1](i, i) = 1;
  R6[2](0, 1) = R6[2](3, 4) = 1;
  R6[2](1, 0) = R6[2](4, 3) = -1;
  N6.bottomLeftCorner<3, 3>() = -skew(Eigen::Vector3d::UnitZ());
  Eigen::Matrix4d R4[3], N4 = Eigen::Matrix4d::Zero();
  for (auto& r : R4) r.setZero();
  R4[0](2, 2) = R4[0](3, 3) = 1;
  R4[1](0, 0) = R4[1](1, 1) = 1;
  R4[2](0, 1) = -1;
  R4[2](1, 0) = 1;
  N4(2, 3) = 1;

  ProjectionCost cost;
  // The stages as the recursion keeps them (stage[0]: the base's, stage[k + 1]: joint k's).
  struct PatternStage {
    std::map<std::pair<int, Mask>, double> Q;  // (kind, pattern) -> number of terms
    std::map<unsigned, double> V, R;           // pattern -> number of terms
    double held = 0;                           // kinetic terms
    double reserved = 0;                       // kinetic terms the recursion reserved for it
  };
  const std::vector<int> children = childCounts(model);
  std::vector<int> pending = children;
  std::vector<PatternStage> stage(n + 1);
  {
    unsigned g = 0;
    for (int a = 0; a < 3; ++a)
      if (model.gravity[a] != 0.0) g |= 1u << a;
    if (g) stage[0].R[g] = 1;
  }
  bool potential = false;  // some potential term is left after a joint
  // The most kinetic terms held at once: the stage being formed (reserved at its bound), the
  // one it starts from, and the others waiting for children (at what was reserved for them;
  // `waiting` sums the reservations of all the stages waiting, the one started from included).
  double stages = 0, waiting = 0;
  for (int k = 0; k < n; ++k) {
    const bool revolute = model.joints[k].type == JointType::Revolute;
    const int parent = model.parent(k);
    PatternStage& in = stage[static_cast<std::size_t>(parent + 1)];
    PatternStage& out = stage[static_cast<std::size_t>(k + 1)];
    // A floating root starts from nothing of the world's stage (its terms: below).
    const PatternStage none;
    const PatternStage& from = isFloatingRoot(model, k) ? none : in;
    const auto& Q = from.Q;
    const auto &V = from.V, &R = from.R;
    auto& Qnext = out.Q;
    auto &Vnext = out.V, &Rnext = out.R;
    const double held = from.held;
    const Eigen::Isometry3d prevPost = parent < 0 ? Eigen::Isometry3d::Identity() : post[parent];
    const Matrix6d Cd = jointMap(prevPost * pre[k]);
    bool C[6][6];
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) C[i][j] = Cd(i, j) != 0.0;
    const int s = revolute ? 2 : 5;
    const bool last = children[static_cast<std::size_t>(k + 1)] == 0;
    // forms[q]: the parameters of link k an entry q of a term reaches
    unsigned forms[21] = {};
    {
      const auto E = linkForms(post[k]);
      for (int i = 0; i < 6; ++i)
        for (int j = i; j < 6; ++j)
          for (int p = 0; p < 10; ++p)
            if (E[p](i, j) != 0.0 || E[p](j, i) != 0.0) forms[kSym.idx[i][j]] |= 1u << p;
    }
    double formed = 0, vterms = 0;
    for (const auto& e : V) vterms += e.second;
    const bool floating = isFloatingRoot(model, k);
    // the recursion reserves the next stage at its bound
    out.reserved = last ? 0.0 : floating ? 21.0 : held * (revolute ? 5 : 3) + vterms * 3 + 1;
    stages = std::max(stages, waiting - in.reserved + held + out.reserved);
    auto add = [&](int kind, Mask m, double count, bool newRow) {
      formed += count;
      unsigned reach = 0;
      for (int q = 0; q < 21; ++q)
        if (m >> q & 1u) reach |= forms[q];
      cost.entries += static_cast<double>(std::bitset<10>(reach).count()) * count;
      if (newRow) cost.rows += count;
      if (!last) Qnext[{kind, m}] += count;
    };
    if (floating) {  // the base twist's products, the twist and the gravity terms (see below)
      for (int a = 0; a < 6; ++a) {
        for (int b = a; b < 6; ++b) add(kAny, 1u << kSym.idx[a][b], 1, true);
        Vnext[1u << a] += 1;
      }
      if (model.gravity.squaredNorm() > 0.0)
        for (int a = 0; a < 4; ++a) {
          Rnext[1u << a] += 1;
          cost.rows += 1;
        }
      for (const auto& e : Qnext) out.held += e.second;
    }
    for (const auto& [km, count] : Q) {
      Mask where = 0;
      for (int i = 0; i < kinds[km.first].count; ++i) where |= 1u << kinds[km.first].idx[i];
      const Mask b = congruencePattern(C, km.second & where);
      if (b == 0) continue;
      if (revolute) {
        Sym6 parts[5];
        double big[5];
        splitRotation(genericOn(b), 0.0, parts, big);
        for (int l = 0; l < 5; ++l)
          if (big[l] > 0.0) add(l, maskOf(parts[l]), count, l != 0);
      } else {
        Matrix6d Bf;
        toFull(genericOn(b), Bf);  // positive entries: the sums below do not cancel
        const Matrix6d Na = N6.cwiseAbs();
        const Matrix6d NB = Na * Bf;
        const Matrix6d parts[3] = {Bf, NB + NB.transpose(), NB * Na.transpose()};
        for (int l = 0; l < 3; ++l) {
          const Mask m = maskOf(toSym(parts[l]));
          if (m != 0) add(kAny, m, count, l != 0);
        }
      }
    }
    if (!floating) Vnext.clear();
    for (const auto& [x, count] : V) {
      const unsigned y = applyPattern<6>(Cd, x, false);
      if (y == 0) continue;
      unsigned parts[3];
      int np;
      if (revolute) {
        for (int a = 0; a < 3; ++a) parts[a] = applyPattern<6>(R6[a], y, false);
        np = 3;
      } else {
        parts[0] = y;
        parts[1] = applyPattern<6>(N6, y, false);
        np = 2;
      }
      for (int l = 0; l < np; ++l) {
        if (parts[l] == 0) continue;
        Vnext[parts[l]] += count;
        Mask cross = 0;
        for (int i = 0; i < 6; ++i)
          if (parts[l] >> i & 1u) cross |= 1u << kSym.idx[i][s];
        add(revolute ? kCross2 : kCross5, cross, count, true);
      }
    }
    if (!floating) {
      Vnext[1u << s] += 1;
      add(revolute ? kDiag2 : kDiag5, 1u << kSym.idx[s][s], 1, true);
      for (const auto& e : Qnext) out.held += e.second;
    }

    const Eigen::Matrix4d Pre = (prevPost * pre[k]).matrix();
    for (const auto& [r, count] : R) {
      const unsigned y = applyPattern<4>(Pre, r, true);
      if (y == 0) continue;
      unsigned parts[3];
      int np;
      if (revolute) {
        for (int a = 0; a < 3; ++a) parts[a] = applyPattern<4>(R4[a], y, true);
        np = 3;
      } else {
        parts[0] = y;
        parts[1] = applyPattern<4>(N4, y, true);
        np = 2;
      }
      for (int l = 0; l < np; ++l)
        if (parts[l] != 0) {
          Rnext[parts[l]] += count;
          if (l != 0) cost.rows += count;
        }
    }
    double rterms = 0;
    for (const auto& e : Rnext) rterms += e.second;
    potential = potential || !Rnext.empty();
    cost.terms += formed + rterms;
    cost.entries += 4 * rterms;
    cost.largest_stage = std::max(cost.largest_stage, formed);
    if (--pending[static_cast<std::size_t>(parent + 1)] == 0) {
      waiting -= in.reserved;
      in = PatternStage();
    }
    if (last)
      out = PatternStage();
    else
      waiting += out.reserved;
  }
  if (potential || layout.rotor) cost.rows += 1;  // the constant
  if (layout.rotor && model.motorSide())          // at most one row per velocity product of a motor
    for (int k = 0; k < model.transmission.nm(); ++k) {
      const double nz = static_cast<double>((model.transmission.T.row(k).array() != 0.0).count());
      cost.rows += nz * (nz + 1) / 2;
      cost.entries += nz * (nz + 1) / 2;
    }
  // Peak memory: two stages of kinetic terms, the entries and keys (vectors grown by doubling,
  // so up to twice their size), then the row reduction's sorted copy of the entries.
  cost.bytes = stages * sizeof(QTerm) + 2.0 * sizeof(InfluenceCoordinates::Entry) * cost.entries +
               2.0 * sizeof(std::uint64_t) * cost.rows + 12.0 * cost.entries;
  return cost;
}

ProjectionLimits projectionLimits() {
  return {kMaxJoints, kMaxTreeJoints, (64 - kL0Bits - 6) / kJointBits, kProjectionMaxParameters};
}

std::string projectionRefusal(const Model& model, ParameterLayout layout, double budget) {
  model.validate();
  if (!recursionTakes(model)) {
    // The method runs on the single-DOF expansion (expandToSingleDof), a floating root kept as
    // it is: its limits apply there.
    const Model expanded = expandToSingleDof(model, true).model;
    std::string why = projectionRefusal(expanded, layout, budget);
    if (!why.empty())
      why += " (model '" + model.name + "' with each multi-DOF joint counted as its chain of " +
             std::to_string(expanded.nq()) + " single-DOF joints in all)";
    return why;
  }
  const int n = model.nq(), P = layout.size(n), nv = model.velocitySize();
  const KeyLayout kl = keyLayout(model);
  const bool floating = hasFloatingRoot(model);
  const std::string has = ", the model has ";
  if (floating && (layout.rotor || layout.friction))
    return "the projection method takes rotor inertia and friction on revolute and prismatic "
           "joints only; model '" +
           model.name + "' has a floating root";
  if (model.isSerial() && !floating && !kl.fits)
    return "the projection method handles at most " + std::to_string(kMaxJoints) + " joints" + has +
           std::to_string(n);
  if ((!model.isSerial() || floating) && nv * (nv + 1) / 2 >= (1 << kL0Bits))
    return "the projection method handles at most " + std::to_string(kMaxTreeJoints) +
           " joints on a tree" +
           (floating ? " (a floating root counted as its six velocities)" + has +
                           std::to_string(nv) + " velocities"
                     : has + std::to_string(n));
  if (!kl.fits)
    return "the projection method handles root paths of up to " +
           std::to_string(projectionLimits().root_path_joints) +
           " joints on a tree, the longest of "
           "this " +
           std::to_string(n) + "-joint tree has " + std::to_string(kl.longest);
  if (P > kProjectionMaxParameters)
    return "the projection method handles at most " + std::to_string(kProjectionMaxParameters) +
           " parameters" + has + std::to_string(P) + " (" + std::to_string(n) + " joints, " +
           std::to_string(layout.perLink()) + " per joint)";
  const ProjectionCost cost = projectionCost(model, layout);
  if (cost.bytes > budget) return overBudget(model, cost, budget);
  return {};
}

InfluenceCoordinates influenceCoordinates(const Model& model, ParameterLayout layout,
                                          double budget) {
  if (!recursionTakes(model)) requireSingleDof(model, "the projection method");
  model.validate();
  const int n = model.nq();
  const std::vector<int> vel = velocityIndex(model);
  const KeyLayout kl = keyLayout(model);
  const bool tree = kl.end_mask != 0;
  {
    const std::string refused = projectionRefusal(model, layout, budget);
    if (!refused.empty())
      throw ModelError(refused +
                       "; the recursive method (method='recursive') gives the same base set, the "
                       "numerical method (method='numerical') a sampled one");
  }
  std::vector<Eigen::Isometry3d> pre, post;
  alignedFrames(model, pre, post);

  // Per-link kinetic parameter forms E'_p (10 per link) in the aligned joint frame.
  const auto& kinds = patterns();
  auto kineticForms = [&](int k) { return TraceForms(linkForms(post[k]), kinds.data(), kKinds); };

  // Rotation by -q about z, as (1, cos, sin) coefficients of the 6x6 twist map.
  Matrix6d R6[3];
  for (auto& r : R6) r.setZero();
  {
    Eigen::Matrix3d P0 = Eigen::Matrix3d::Zero(), P1 = Eigen::Matrix3d::Zero(),
                    P2 = Eigen::Matrix3d::Zero();
    P0(2, 2) = 1;
    P1(0, 0) = P1(1, 1) = 1;
    P2(0, 1) = 1;
    P2(1, 0) = -1;
    const Eigen::Matrix3d* Ps[3] = {&P0, &P1, &P2};
    for (int a = 0; a < 3; ++a) {
      R6[a].topLeftCorner<3, 3>() = *Ps[a];
      R6[a].bottomRightCorner<3, 3>() = *Ps[a];
    }
  }
  // Translation by -q along z on twists: v -> v - q z x w.
  Matrix6d N6 = Matrix6d::Zero();
  N6.bottomLeftCorner<3, 3>() = -skew(Eigen::Vector3d::UnitZ());
  // Homogeneous rotation by +q about z and translation by +q along z, for g~^T T.
  Eigen::Matrix4d R4[3];
  for (auto& r : R4) r.setZero();
  R4[0](2, 2) = R4[0](3, 3) = 1;
  R4[1](0, 0) = R4[1](1, 1) = 1;
  R4[2](0, 1) = -1;
  R4[2](1, 0) = 1;
  Eigen::Matrix4d N4 = Eigen::Matrix4d::Zero();
  N4(2, 3) = 1;

  // The stage after each joint, kept until its last child joint has started from it (a serial
  // chain keeps one at a time); stage[0] is the base's, stage[k + 1] joint k's. The stage a
  // joint starts from and the one it forms are moved into Q, V, R and Qnext, Vnext, Rnext for
  // the joint; the vectors of a finished stage are reused for the next one formed.
  const std::vector<int> children = childCounts(model);
  std::vector<int> pending = children;  // children yet to start from each stage
  std::vector<Stage> stage(n + 1);
  std::vector<QTerm> Q, Qnext;
  std::vector<VTerm> V, Vnext;
  std::vector<RTerm> R, Rnext;
  Row4d g0;
  g0 << model.gravity.transpose(), 0.0;
  stage[0].R.push_back({0, -1, g0});

  std::vector<std::uint64_t> keys;
  std::vector<Entry> entries;
  std::vector<int> slotRow;  // row of each shared slot (-1: none yet), see Stage
  auto rowOf = [&keys, &slotRow](auto& term) {
    if (term.row < 0) {
      if (term.row == -1) {
        term.row = static_cast<int>(keys.size());
        keys.push_back(term.key);
      } else {
        int& row = slotRow[static_cast<std::size_t>(-2 - term.row)];
        if (row < 0) {
          row = static_cast<int>(keys.size());
          keys.push_back(term.key);
        }
        term.row = row;
      }
    }
    return term.row;
  };
  // A stage that several children start from gives each of its terms without a row a slot:
  // their constant-factor parts in every branch are the same basis function, hence one row.
  auto share = [&slotRow](Stage& st) {
    auto give = [&slotRow](auto& terms) {
      for (auto& t : terms)
        if (t.row == -1) {
          t.row = -2 - static_cast<int>(slotRow.size());
          slotRow.push_back(-1);
        }
    };
    give(st.Q);
    give(st.R);
  };
  if (children[0] > 1) share(stage[0]);
  InfluenceCoordinates out;
  out.layout = layout;
  out.n = n;
  if (tree) {  // a tree, or a chain under a floating root: keys with their deepest joint
    out.parents.resize(static_cast<std::size_t>(n));
    for (int k = 0; k < n; ++k) out.parents[static_cast<std::size_t>(k)] = model.parent(k);
    out.end_shift = kl.end_shift;
  }

  // The joints, in index order; compiled apart for serial chains, whose keys need no path.
  auto run = [&](auto treeKeys) {
    constexpr bool kTree = decltype(treeKeys)::value;
    for (int k = 0; k < n; ++k) {
      const bool revolute = model.joints[k].type == JointType::Revolute;
      const int parent = model.parent(k);
      Stage& in = stage[static_cast<std::size_t>(parent + 1)];
      Q.swap(in.Q);  // Q, V and R are empty here
      V.swap(in.V);
      R.swap(in.R);
      const Eigen::Isometry3d prevPost = parent < 0 ? Eigen::Isometry3d::Identity() : post[parent];
      const Matrix6d Cd = jointMap(prevPost * pre[k]);
      const double cscale = std::max(1.0, maxAbs(Cd));
      const Sparse6 C(Cd);
      const int s = revolute ? 2 : 5;  // the joint's twist is S = e_s
      const Vector6d S = Vector6d::Unit(s);
      // The key of part l (0: the constant factor, the same key) of a term through this joint,
      // and the key of a function of this joint's rate.
      const int shift = kl.shift[static_cast<std::size_t>(k)];
      const std::uint64_t others = ~kl.end_mask,
                          end = kl.end_mask & (static_cast<std::uint64_t>(k + 1) << kl.end_shift);
      auto through = [=](std::uint64_t key, int l) {
        if constexpr (!kTree)
          return key | (static_cast<std::uint64_t>(l) << shift);
        else
          return l == 0 ? key : (key & others) | end | (static_cast<std::uint64_t>(l) << shift);
      };

      // Every new kinetic term is projected on link k's parameters at once and kept for the
      // joint's children (for a leaf, not kept).
      const bool last = children[static_cast<std::size_t>(k + 1)] == 0;
      const int c0 = k * layout.perLink();
      const auto E = kineticForms(k);
      const std::size_t most = Q.size() * (revolute ? 5 : 3) + V.size() * 3 + 1;
      const std::size_t rmost = R.size() * (revolute ? 3 : 2);
      if (entries.size() + 10 * most + 4 * rmost > entries.capacity())
        entries.reserve(std::max(entries.size() + 10 * most + 4 * rmost, 2 * entries.capacity()));
      if (keys.size() + most + rmost > keys.capacity())
        keys.reserve(std::max(keys.size() + most + rmost, 2 * keys.capacity()));
      int formed = 0;
      // A term gets its row of Z with its first coordinate (its constant-factor part carries the
      // key on, hence the row once it has one).
      auto add = [&](QTerm& t) {
        ++formed;
        double v[10];
        const unsigned touched = E(t.Q, t.kind, v);
        const double tol = kNoise * t.scale;
        unsigned keep = 0;
        for (int p = 0; p < 10; ++p)
          if ((touched >> p & 1u) && std::abs(v[p]) > tol) keep |= 1u << p;
        if (keep != 0) {
          const int row = rowOf(t);
          for (int p = 0; p < 10; ++p)
            if (keep >> p & 1u) entries.push_back({row, c0 + p, v[p]});
        }
        if (!last) Qnext.push_back(t);
      };

      // Kinetic part: Q_k = Ad Q_parent(k) Ad^T + cross terms + 2 S S^T dq_k^2.
      Qnext.clear();
      if (!last) Qnext.reserve(most);
      // A floating root starts from nothing of the world's stage: its terms are formed below.
      const bool floating = isFloatingRoot(model, k);
      std::vector<QTerm> worldQ;
      std::vector<VTerm> worldV;
      std::vector<RTerm> worldR;
      if (floating) {
        worldQ.swap(Q);
        worldV.swap(V);
        worldR.swap(R);
      }
      for (const QTerm& t : Q) {
        Sym6 B;
        C.congruence(t.Q, kinds[t.kind], B);
        const double bscale = pruneMax(B, kNoise * t.scale * cscale * cscale);
        if (bscale == 0.0) continue;
        const double ptol = kNoise * bscale;
        Sym6 parts[5];
        double ps[5];
        int count;
        if (revolute) {
          splitRotation(B, ptol, parts, ps);
          count = 5;
        } else {
          Matrix6d Bf;
          toFull(B, Bf);
          const Matrix6d NB = N6 * Bf;
          parts[0] = B;
          parts[1] = toSym(NB + NB.transpose());
          parts[2] = toSym(NB * N6.transpose());
          count = 3;
          for (int l = 0; l < count; ++l) ps[l] = pruneMax(parts[l], ptol);
        }
        // The constant factor (l = 0) keeps the key and the row.
        for (int l = 0; l < count; ++l)
          if (ps[l] > 0.0) {
            QTerm part{through(t.key, l), l == 0 ? t.row : -1,
                       static_cast<std::uint8_t>(revolute ? l : kAny), ps[l], parts[l]};
            add(part);
          }
      }
      Vnext.clear();
      Vnext.reserve(V.size() * 3 + 1);
      for (const VTerm& t : V) {
        Vector6d y;
        C.apply(t.x, y);
        if (!prune(y, kNoise * maxAbs(t.x) * cscale)) continue;
        Vector6d parts[3];
        const int count = jointParts(revolute, y, parts,
                                     [&](int a) -> Vector6d { return a < 3 ? R6[a] * y : N6 * y; });
        const double ptol = kNoise * maxAbs(y);
        for (int l = 0; l < count; ++l) {
          if (!prune(parts[l], ptol)) continue;
          const std::uint64_t key = through(t.key, l);
          Vnext.push_back({t.i, key, parts[l]});
          // x S^T + S x^T
          QTerm cross{withL0(kTree ? (key & others) | end : key,
                             pairIndex(vel[static_cast<std::size_t>(k)], t.i)),
                      -1,
                      revolute ? kCross2 : kCross5,
                      0.0,
                      {}};
          for (int i = 0; i < 6; ++i) {
            const double v = i == s ? 2.0 * parts[l][i] : parts[l][i];
            cross.Q[kSym.idx[i][s]] = v;
            cross.scale = std::max(cross.scale, std::abs(v));
          }
          add(cross);
        }
      }
      const int vk = vel[static_cast<std::size_t>(k)];
      QTerm diagonal{withL0(end, pairIndex(vk, vk)), -1, revolute ? kDiag2 : kDiag5, 2.0, {}};
      diagonal.Q[kSym.idx[s][s]] = 2.0;
      if (!floating) {
        Vnext.push_back({vk, 0, S});
        if (layout.rotor) rowOf(diagonal);  // Ia_k's coordinate is on this row
        add(diagonal);
      }

      // Potential part: g~^T T_k.
      Rnext.clear();
      Rnext.reserve(R.size() * 3);
      const Eigen::Matrix4d Pre = (prevPost * pre[k]).matrix(), Post = post[k].matrix();
      for (const RTerm& t : R) {
        Row4d y = t.r * Pre;
        if (!prune(y, kNoise * maxAbs(t.r) * std::max(1.0, maxAbs(Pre)))) continue;
        Row4d parts[3];
        const int count = jointParts(revolute, y, parts,
                                     [&](int a) -> Row4d { return a < 3 ? y * R4[a] : y * N4; });
        const double ptol = kNoise * maxAbs(y);
        for (int l = 0; l < count; ++l)
          if (prune(parts[l], ptol))
            Rnext.push_back({through(t.key, l), l == 0 ? t.row : -1, parts[l]});
      }
      if (floating) {
        // The floating body's twist v (angular; linear, in its moved frame): six independent
        // velocities, T = 1/2 v^T M v, the products v_a v_b on link k. Its potential,
        // g^T T_k = |g| (u^T, h): u = R^T g / |g| (on the sphere, so its three components are
        // independent functions) and h = g . p / |g|, four functions of its configuration.
        for (int a = 0; a < 6; ++a)
          for (int b = a; b < 6; ++b) {
            const int i = floatingVelocity(vk, a), j = floatingVelocity(vk, b);
            QTerm t{withL0(end, pairIndex(std::max(i, j), std::min(i, j))),
                    -1,
                    kAny,
                    a == b ? 2.0 : 1.0,
                    {}};
            t.Q[kSym.idx[a][b]] = t.scale;
            add(t);
          }
        for (int a = 0; a < 6; ++a)
          Vnext.push_back({floatingVelocity(vk, a), 0, Vector6d::Unit(a)});
        if (const double g = model.gravity.norm(); g > 0.0)
          for (int a = 0; a < 4; ++a) {
            Row4d r = Row4d::Zero();
            r[a] = g;
            Rnext.push_back({end | (static_cast<std::uint64_t>(a + 1) << shift), -1, r});
          }
        Q.swap(worldQ);
        V.swap(worldV);
        R.swap(worldR);
      }
      out.terms_formed += formed + static_cast<int>(Rnext.size());

      // Project link k's potential parameters.
      for (RTerm& t : Rnext) {
        const Row4d r = t.r * Post;
        const double scale = maxAbs(t.r) * std::max(1.0, maxAbs(Post));
        for (int a = 0; a < 4; ++a)
          if (std::abs(r[a]) > kNoise * scale) entries.push_back({rowOf(t), c0 + 6 + a, r[a]});
      }
      if (layout.rotor && !model.motorSide() && !floating)  // on 0.5 dq_k^2
        entries.push_back({diagonal.row, layout.rotorIndex(k), 1.0});
      if (!last) {
        Stage& next = stage[static_cast<std::size_t>(k + 1)];
        next.Q.swap(Qnext);  // Qnext, Vnext and Rnext are left empty
        next.V.swap(Vnext);
        next.R.swap(Rnext);
        if (children[static_cast<std::size_t>(k + 1)] > 1) share(next);
      }
      // The parent's stage is done once its last child has started from it; otherwise it goes
      // back for the next child.
      if (--pending[static_cast<std::size_t>(parent + 1)] == 0) {
        if (!last) {  // its vectors serve for the next stage formed
          Qnext.swap(Q);
          Vnext.swap(V);
          Rnext.swap(R);
        } else {  // a leaf's stage is not kept: its vectors serve instead
          std::vector<QTerm>().swap(Q);
          std::vector<VTerm>().swap(V);
          std::vector<RTerm>().swap(R);
        }
      } else {
        in.Q.swap(Q);
        in.V.swap(V);
        in.R.swap(R);
      }
    }
  };
  if (tree)
    run(std::true_type{});
  else
    run(std::false_type{});

  // Rotor inertia on the motors. Motor k's rotor has the kinetic energy
  //   1/2 Ia_k (t_k . dq)^2 = Ia_k [ sum_a t_ka^2 (1/2 dq_a^2) + sum_{a > b} t_ka t_kb (dq_a dq_b)
  //   ],
  // a form in dq whose factors of q are all constant: in the basis, Ia_k's coordinates are
  // t_ka^2 on the function 1/2 dq_a^2 (l0 = J(a, a), every lk = 1), the row of a joint-side rotor
  // inertia, and t_ka t_kb on dq_a dq_b (l0 = J(a, b), every lk = 1). A diagonal T (t_k = r e_k)
  // gives r^2 times the joint-side coordinate, so the rotor regroups as on the joints; a coupled
  // row reaches the functions dq_a dq_b of its joints, where the links' coordinates (the constant
  // part of their kinetic energy's dq_a dq_b coefficient) are (a row made here if the links
  // have none there: those functions are then the rotor's alone). On a tree, dq_a dq_b of joints
  // on different root paths is no link's function: a row of the rotors alone, kept like a
  // function of the deeper joint. The functions of the basis stay independent, so the
  // coordinates are exact and the echelon form regroups the rotors with the links as it does the
  // links among themselves.
  if (layout.rotor && model.motorSide()) {
    const Eigen::MatrixXd& T = model.transmission.T;
    std::map<std::uint64_t, int> wanted;  // key -> row (-1: not found yet)
    auto keyOf = [&](int a, int b) {      // 0-based joints, a >= b
      std::uint64_t key = static_cast<std::uint64_t>(
          pairIndex(vel[static_cast<std::size_t>(a)], vel[static_cast<std::size_t>(b)]));
      if (tree) key |= kl.end_mask & (static_cast<std::uint64_t>(a + 1) << kl.end_shift);
      return key;
    };
    for (int k = 0; k < n; ++k)
      for (int a = 0; a < n; ++a)
        for (int b = 0; b <= a && T(k, a) != 0.0; ++b)
          if (T(k, b) != 0.0) wanted.emplace(keyOf(a, b), -1);
    for (std::size_t r = 0; r < keys.size(); ++r) {
      const auto it = wanted.find(keys[r]);
      if (it != wanted.end() && it->second < 0) it->second = static_cast<int>(r);
    }
    for (auto& [key, row] : wanted)
      if (row < 0) {
        row = static_cast<int>(keys.size());
        keys.push_back(key);
      }
    for (int k = 0; k < n; ++k)
      for (int a = 0; a < n; ++a)
        for (int b = 0; b <= a && T(k, a) != 0.0; ++b)
          if (T(k, b) != 0.0)
            entries.push_back({wanted.at(keyOf(a, b)), layout.rotorIndex(k), T(k, a) * T(k, b)});
    // A row's coordinates by ascending column (the rotor's column may come before the links').
    std::sort(entries.begin(), entries.end(), [](const Entry& x, const Entry& y) {
      return x.row != y.row ? x.row < y.row : x.col < y.col;
    });
  }

  out.keys = std::move(keys);
  out.entries = std::move(entries);
  return out;
}

}  // namespace mindyn
