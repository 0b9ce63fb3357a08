// Base inertial parameters: echelon form of the coordinate matrix, the regrouping matrix Y, the
// Lagrangian / total-energy / equations-of-motion sets, readable formulas, and the base
// regressors. Three methods: the exact projection method (projection.hpp), the exact recursive
// method (recursive_base.hpp: the identifiable space link by link, cost linear in the number of
// links, then the same echelon form) and the sampled numerical method (regressor samples, QR),
// for cross-checking.
//
// Multi-DOF joints: the exact methods run on the single-DOF expansion (expandToSingleDof) and
// keep the real links' columns (docs/base-parameters.md, "Joints of several degrees of
// freedom"); rotor inertia and friction are refused there.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <limits>
#include <string>
#include <vector>

#include "mindyn/data.hpp"
#include "mindyn/dynamics.hpp"
#include "mindyn/model.hpp"
#include "mindyn/projection.hpp"

namespace mindyn {

/// Outcome of one rank decision by Gaussian elimination with partial pivoting, columns offered
/// in a priority order. Sizes of pivots are relative to the column's own largest entry, so the
/// decision does not depend on the units of the parameters.
struct RankDecision {
  double tolerance = 0;
  std::vector<int> pivots;         // kept columns (classical indices), in the order they were kept
  std::vector<double> pivot_size;  // relative pivot of each kept column
  std::vector<int> dependent;      // non-zero columns that are combinations of earlier pivots
  std::vector<double> residual;    // their relative residuals
  std::vector<int> zero;           // columns that are identically zero: no effect at all
  double smallest_kept = std::numeric_limits<double>::infinity();
  double largest_dropped = 0;
  int rank_looser = -1;   // rank with tolerance x 1e4
  int rank_tighter = -1;  // rank with tolerance x 1e-3
  // Columns are also compared with the largest column of their kind (inertia, first moment,
  // mass, ...): a kept column that is tiny for its kind (a joint axis tilted by rounding) is weak.
  double weakest_kept = std::numeric_limits<double>::infinity();  // pivot x norm / kind's largest
  double zero_threshold = 0;  // columns up to this (entries relative to their rows) count as zero
  double largest_zeroed = 0;  // largest such non-zero column size, relative; 0 if all exact
  bool near_degenerate = false;
  // The columns (classical indices, in priority order) whose decision the neighbouring
  // tolerances change: a base parameter at this tolerance and not at one of them, or the other
  // way round, or weak; empty when neither changes any.
  std::vector<int> undecided;
  Eigen::SparseMatrix<double> Y;  // rank x columns, Y.col(pivots[b]) = e_b; mostly zero
  double fit_residual = 0;        // max |Z - Z~ Y| relative to max |Z|
  // W_b Y = W checked against the classical model (computeBaseParameters): the largest
  // difference of the regrouped dynamics from the classical one at random states, relative to
  // the largest value; 0 from echelon alone.
  double consistency = 0;
  // The column whose regrouping leaves the largest residual in Z (with the rounding of
  // evaluating Z~ Y), each entry relative to its row in the units of the parameters.
  int worst_column = -1;
  int rank() const { return static_cast<int>(pivots.size()); }
};

/// Relative tolerance of the rank decisions (see RankDecision).
inline constexpr double kDefaultRankTolerance = 1e-9;

/// Gaussian elimination of the columns of Z in `order` (a permutation of all column indices).
/// `kinds` optionally groups the columns (same value: same kind of parameter) for the
/// weak-column report.
///
/// `units` (optional, one positive number per column, e.g. columnUnits) gives each column the
/// size of its coordinates for parameters of unit size in the robot's own length scale: a
/// coordinate is compared with the others of its row in those units. A residual is kept as a
/// pivot only when it is above the tolerance both relative to its own column and relative to its
/// rows in those units, and relative to the largest row (the scale of the whole robot: a row that
/// is all small, gravity times an axis tilted 1e-12 rad, no rank decision on the regressor
/// resolves); a column whose entries are all below 1e-13 of their rows counts as zero.
/// Without `units`, every column counts as of unit size. `scale` (optional, > 0) is that largest
/// row when it is another matrix's (the Lagrangian's coordinates measured against the rows that
/// reach the torques, without the constant potential); 0: the largest row of Z; negative: none,
/// for rows that are directions each normalised on its own (the recursive method's), which no
/// row measures another's size.
RankDecision echelon(const Eigen::MatrixXd& Z, const std::vector<int>& order,
                     double tolerance = kDefaultRankTolerance, const std::vector<int>& kinds = {},
                     const Eigen::VectorXd& units = {}, double scale = 0);
/// The same on a sparse Z (only its non-zero entries are stored and visited).
RankDecision echelon(const Eigen::SparseMatrix<double>& Z, const std::vector<int>& order,
                     double tolerance = kDefaultRankTolerance, const std::vector<int>& kinds = {},
                     const Eigen::VectorXd& units = {}, double scale = 0);

/// The largest row of Z in the units of the parameters (max over rows and columns of
/// |Z(r, c)| / units[c]): the scale echelon measures residuals against.
double largestRow(const Eigen::SparseMatrix<double>& Z, const Eigen::VectorXd& units);

/// Size of each column's coordinates in units of the robot's length L (its longest root path,
/// joint offsets and prismatic travel added up from the base, rounded to a power of two): L^2 for
/// the mass, L for the first moments, 1 for the inertia and rotor inertia, L for friction (the
/// numerical method samples it at the rates as given, the other columns at those of the
/// unit-length model, time in sqrt(L / 1 m) s); L^2 for the rotor inertia and friction of a
/// prismatic joint, or of a motor driving only prismatic joints, which act on a force as a mass
/// does. Powers of two, so that scaling by them is exact.
Eigen::VectorXd columnUnits(const Model& model, ParameterLayout layout);

/// The conventional (Khalil) priority order: link by link from the base; in each link
/// XX XY XZ YZ ZZ MX MY, then YY MZ M, then Ia, Fv, Fc; then the joint block (offsets).
std::vector<int> khalilOrder(int n, ParameterLayout layout);

enum class BaseMethod { Projection, Numerical, Recursive };

struct BaseOptions {
  ParameterLayout layout;
  /// A permutation of the link parameters (layout.linkSize(n) entries); empty: khalilOrder.
  /// The joint block (torque offsets) follows them, each offset a base parameter of its own.
  std::vector<int> order;
  double tolerance = kDefaultRankTolerance;
  BaseMethod method = BaseMethod::Projection;
  int samples = 0;    // numerical method: number of random states (0: automatic)
  unsigned seed = 1;  // numerical method: random seed
  double projection_budget = kProjectionBudget;  // bytes, projection method
  // bytes, numerical method: 2 GiB, a chain of about 340 joints (200 joints: 0.7 GiB, 14 s)
  double numerical_budget = 2.0 * 1024 * 1024 * 1024;
};

/// One base-parameter set with its names.
struct BaseSet {
  RankDecision decision;
  std::vector<std::string> names;  // e.g. XXR3, ZZ1, Fv2
  int size() const { return decision.rank(); }
  /// The regrouping formulas, one per base parameter ("XXR3 = XX3 - YY3 + ...", see
  /// formatFormula), written on request from the rows of Y.
  std::vector<std::string> formulas(const std::vector<std::string>& classical_names) const;
};

struct BaseParameters {
  ParameterLayout layout;
  std::vector<std::string> classical_names;
  BaseMethod method = BaseMethod::Projection;
  BaseSet lagrangian, energy, eom;  // the three sets; eom is the one used for dynamics
  bool lagrangian_equals_energy = false;
  bool lagrangian_equals_eom = false;
  int basis_rows = 0;  // projection: non-zero basis functions; numerical: stacked rows
  /// What snapRightAngles would change (rotations or axes within 1e-3 of right angles that are
  /// not exactly right), so that a near-degenerate report suggests snapping only where it applies.
  std::vector<std::string> snappable;
  int terms_formed = 0;  // projection: terms produced by the recursion
  double seconds = 0;    // wall time of the computation

  /// p_b = Y pi for the equations-of-motion set.
  Eigen::VectorXd values(const Eigen::Ref<const Eigen::VectorXd>& classical) const;
  /// A classical vector with p_b at the pivots and zeros elsewhere (Y embed(p_b) = p_b).
  Eigen::VectorXd embed(const Eigen::Ref<const Eigen::VectorXd>& base) const;
};

/// Computes the three sets. Each is checked before it is returned: W_b Y must reproduce the
/// classical coordinates (RankDecision::consistency within the tolerance); a set that does not --
/// near-degenerate geometry whose regrouping cannot be evaluated to the tolerance -- is refused
/// with a ModelError that says which column, how far, and what to do.
BaseParameters computeBaseParameters(const Model& model, const BaseOptions& options = {});

/// Formula text "NAME = c1*P1 + c2*P2 ...": exact zeros dropped, +-1 written as signs,
/// coefficients at full (shortest round-trip) precision.
std::string formatFormula(const std::string& name, const Eigen::Ref<const Eigen::RowVectorXd>& row,
                          const std::vector<std::string>& classical_names);

/// Base regressor W_b = W(:, pivots) of the equations-of-motion set: tau = W_b p_b.
/// `W` is an n x layout.size(n) work matrix. Allocates nothing.
void baseRegressor(const Model& model, Data& data, const BaseParameters& base, const VecRef& q,
                   const VecRef& dq, const VecRef& ddq, MatOut W, MatOut Wb) noexcept;

/// Base total-energy regressor row w_H,b = (w_K + w_P)(:, pivots) of the equations-of-motion
/// set (the set used by the energy-difference identification model). Allocates nothing.
void baseEnergyRegressor(const Model& model, Data& data, const BaseParameters& base,
                         const VecRef& q, const VecRef& dq, VecOut wK, VecOut wP,
                         VecOut wb) noexcept;

/// One angle or axis component that snapRightAngles rounds.
struct SnapChange {
  int joint = 0;           // 0-based joint index
  std::string joint_name;  // its name
  std::string frame;       // "origin" (the rotation before the joint motion), "link frame" (the
                           // one after it) or "axis"
  std::string component;   // "yaw", "pitch", "roll" (of the rotation Rz(yaw) Ry(pitch) Rx(roll))
                           // or "x", "y", "z" (of the axis)
  double value = 0;        // the angle [rad] or axis component as the model has it
  double snapped = 0;      // what the snap makes of it (a multiple of pi/2, or 0)
  double deviation = 0;    // |value - snapped|, in (0, tolerance]
};

/// Rounds joint-origin rotations that are within `tolerance` [rad] of multiples of pi/2 (per
/// roll-pitch-yaw angle) and axis components within `tolerance` of 0 or +-1; returns one line per
/// change made (text for display) and, when `changes` is given, appends to it each angle and axis
/// component rounded (the same changes as data).
std::vector<std::string> snapRightAngles(Model& model, double tolerance = 1e-3,
                                         std::vector<SnapChange>* changes = nullptr);

}  // namespace mindyn
