// The projection kernel: exact coordinates of every influence coefficient of the Lagrangian in
// the basis of F_L = Y0 x Y1 x ... x Yn (method: docs/base-parameters.md).
//
// Basis functions are multi-indices (l0; l1 .. ln):
//   l0 = 0        the constant 1 (potential part);
//   l0 = J(i, j)  = i(i-1)/2 + j, 1 <= j <= i <= nv: 0.5 dq_i^2 when i == j, dq_i dq_j otherwise;
//   lk in 1..5    1, cos q_k, sin q_k, cos 2q_k, sin 2q_k for a revolute joint k;
//   lk in 1..3    1, q_k, q_k^2 for a prismatic joint k.
// The coordinates are computed by a recursion over the joints on the body twists (kinetic part)
// and on g~^T T_k (potential part): each joint multiplies by a matrix affine in (1, cos, sin) or
// (1, q), which maps a term to at most five terms. No sampling, no regressor evaluation. Terms
// whose coefficients vanish are dropped, so only the non-zero rows are ever formed.
// On a tree, each joint starts from the stage of its parent joint (siblings branch from the
// same stage): a link's energies involve only the joints of its root path, so J(i, j) occurs
// only for i and j on one root path, and lk = 1 for every joint off the path. A basis function
// that does not involve a branch is one row, whichever branches give it coordinates.
//
// A model with multi-DOF joints runs as its single-DOF expansion (expandToSingleDof, model.hpp;
// the basis functions of each pair and why the real links' columns suffice:
// docs/base-parameters.md, "Joints of several degrees of freedom"); its joints are counted there.
// A free-flyer hanging from the world (a floating base) is taken as it is: the body's twist v
// (six velocities, Pinocchio's v order in the products' numbering) starts its stage, and its
// potential is |g| times the four functions u = R^T g / |g| (three components, independent on
// the sphere) and h = g . p / |g| of its configuration, the factor of the free-flyer in the keys
// (lk = 2..5: ux, uy, uz, h). The kinetic energy depends on the body's configuration only
// through v, so no chart and none of its trigonometric products enter (docs/base-parameters.md,
// "A floating base").
//   l0 = J(i, j) numbers velocities, not joints: i, j are 1-based indices of v.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "mindyn/model.hpp"

namespace mindyn {

/// One basis function of F_L.
struct BasisFunction {
  int l0 = 0;                                      // 0: constant; J(i, j) for the velocity product
  std::vector<int> l;                              // per joint, 1-based index into its Y_k
  std::string toString(const Model& model) const;  // e.g. "dq1*dq2*cos(q2)*sin(2q3)"
};

/// Coordinates of the classical influence coefficients of the Lagrangian, w_L = w~ Z.
/// Rows: the non-zero basis functions (a row is made with a term's first non-zero coordinate);
/// columns: the classical parameters in `layout` (friction columns, which are not in the
/// Lagrangian, are zero here).
struct InfluenceCoordinates {
  struct Entry {
    int row, col;
    double value;
  };
  ParameterLayout layout;
  int n = 0;
  std::vector<std::uint64_t> keys;  // packed multi-index of each row
  std::vector<Entry> entries;       // the non-zero coordinates; a row's by ascending column
  int terms_formed = 0;             // kinetic + potential terms produced by the recursion
  /// A tree's (or a chain's under a floating root): the parent of each joint (empty for a
  /// serial chain's keys) and where its keys keep the
  /// deepest joint they involve; its keys give each joint's factor at the joint's position on
  /// its root path (for a serial chain, at the joint's index, as packBasis).
  std::vector<int> parents;
  int end_shift = 0;
  int rows() const { return static_cast<int>(keys.size()); }
  int cols() const { return layout.size(n); }
  /// Z as a dense matrix (rows x cols); large for long chains.
  Eigen::MatrixXd dense() const;
  /// Index of the row of the constant function 1, or -1 if that row is zero.
  int constantRow() const;
  BasisFunction basis(int row) const;
  /// The last joint (1-based) a row's basis function involves, through q or dq; 0 for the
  /// constant. The joints it involves lie on that joint's root path; the row's coordinates lie
  /// on the links that joint carries (its link and those of its descendants, numbered after
  /// it), so columns of links before it are zero on that row.
  int depth(int row) const;
};

/// What the recursion of influenceCoordinates will form, counted beforehand on the sparsity
/// patterns of the terms (no values), stage by stage as the recursion keeps them (on a tree,
/// the stages waiting for further children count in the memory): every count is an upper bound,
/// reached for generic geometry; exact zeros of special geometry (axis-aligned frames) are seen,
/// cancellations of values are not. The basis grows geometrically along runs of parallel or
/// general joint axes.
struct ProjectionCost {
  double terms = 0;          // kinetic and potential terms formed (terms_formed)
  double rows = 0;           // non-zero basis functions (rows of Z)
  double entries = 0;        // non-zero coordinates
  double largest_stage = 0;  // most kinetic terms held by one joint's stage
  double bytes = 0;          // peak memory of the recursion and of the row reduction after it
};
ProjectionCost projectionCost(const Model& model, ParameterLayout layout = {});

/// Memory the projection method may use by default: 8 GiB, half of a 16 GiB workstation. The
/// estimate is an upper bound: for generic 8-11 joint chains it is 1-3 times the measured peak
/// (a generic 11-joint chain: estimate 6.2 GB, measured 2.2 GB, 11 s), for planar arms up to
/// ten times; a generic 12-joint chain (estimate 31 GB) is refused.
inline constexpr double kProjectionBudget = 8.0 * 1024 * 1024 * 1024;

/// Most parameters (columns, friction included) the projection method's row reduction takes:
/// it groups rows by bit masks of their columns, of 11 words of 64 bits. That is more than a
/// tree of the most joints the basis index holds (44) has with every per-joint column (ten
/// inertial, rotor inertia, three friction, an offset: 660), so the joint limits and the memory
/// budget refuse a model first; the masks are a fixed size so that grouping allocates nothing
/// per row.
inline constexpr int kProjectionMaxParameters = 11 * 64;

/// The projection method's limits on a model, besides its memory budget (kProjectionBudget):
/// most joints of a serial chain (its packed basis index), of a tree, and on one root path of
/// a tree; most parameters (kProjectionMaxParameters). projectionRefusal checks them; they are
/// here so that texts describing the method (the command line's help) read them.
struct ProjectionLimits {
  int chain_joints;
  int tree_joints;
  int root_path_joints;
  int parameters;
};
ProjectionLimits projectionLimits();

/// Why the projection method cannot take `model` in `layout` with `budget` bytes, or an empty
/// string when it can: every limit it has, in one place, checked before computing in the order
/// the method meets them: joints (18 on a serial chain, the packed index; 44 on a tree and 16 on
/// one root path), parameters (kProjectionMaxParameters) and memory (projectionCost's estimate
/// against `budget`). The text starts with "the projection method" and names the limit and the
/// model's value ("the projection method handles at most 18 joints, the model has 20").
std::string projectionRefusal(const Model& model, ParameterLayout layout = {},
                              double budget = kProjectionBudget);

/// Runs the recursion. Throws ModelError, before forming anything, when projectionRefusal
/// refuses the model.
InfluenceCoordinates influenceCoordinates(const Model& model, ParameterLayout layout = {},
                                          double budget = kProjectionBudget);

/// Packs (l0; l1..ln) into a key and back, as a serial chain's keys are packed.
std::uint64_t packBasis(int l0, const std::vector<int>& l);
BasisFunction unpackBasis(std::uint64_t key, int n);

}  // namespace mindyn
