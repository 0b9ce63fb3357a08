// The identifiable subspace of the classical parameters by a recursion over the links (the
// recursive parameter nullspace algorithm of Wensing, Niemeyer and Slotine, IJRR 2018), exact and
// of cost linear in the number of links, on serial chains and on trees. Its rows feed the same
// echelon form as the projection method's coordinates (base_parameters.hpp), so both give the
// same base set and the same Y.
//
// Per link k, in its own frame (p = parent(k): the link that joint k moves link k against, the
// fixed base when p = -1):
//   V_k  the span of the spatial motions link k can have (velocities, and gravity taken as an
//        acceleration of the fixed base), carried over joint k from V_p and closed under joint
//        k's motion;
//   N_k  the functionals of link k's inertia that joint k's torque or the motion of joint k
//        relative to link p reveal: s_k^T I v for v in V_k, and the rate under joint k's motion
//        of what link p identifies;
//   C_k  everything identifiable about link k's inertia: N_k and what link p identifies of it
//        at q_k = 0.
// The nullspace of the regressor is spanned by each link's null(C_k) and by the inertia in
// null(N_k) moved rigidly over joint k to link p. Its orthogonal complement, the identifiable
// space, is then spanned by the rows n T_{j,k} on the links k of the subtree of link j (j and
// its descendants) for every row n of a basis of N_j: n applied to the inertia of that subtree
// carried into frame j at q = 0 (T_{j,k}: the parameters of link k expressed in frame j). Rotor
// inertia and friction are added as columns of their own (see recursiveIdentifiable), on the
// motor side through the transmission (recursive_base.cpp).
//
// A model with multi-DOF joints runs as its single-DOF expansion (expandToSingleDof, model.hpp;
// docs/base-parameters.md, "Joints of several degrees of freedom"): computeBaseParameters keeps
// the real links' columns of its rows, which need not be independent there.
//
// Notation (frames, vector orders, units, parameter layouts): docs/notation.md.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>
#include <vector>

#include "mindyn/model.hpp"

namespace mindyn {

struct IdentifiableSpace {
  /// Rows spanning the identifiable space of the equations of motion (layout columns), link by
  /// link from the base: the rows of link j are zero outside the columns of its subtree (sparse:
  /// only the non-zero entries are stored).
  Eigen::SparseMatrix<double> rows;
  /// The constant part of the Lagrangian as a functional of the parameters (the potential energy
  /// averaged over the revolute joints, at q = 0 for the prismatic ones); with the rows without
  /// friction it spans the identifiable space of the Lagrangian and of the total energy.
  Eigen::RowVectorXd constant;
  std::vector<int> link_rank;        // rank of N_k per link: its number of base parameters
  std::vector<int> rotor_regrouped;  // joints whose rotor inertia regroups with link inertia
  /// Margins of the recursion's own rank decisions: the singular values of each span's vectors,
  /// each relative to the size of what produced it and weighted by the size of the torques it
  /// stands for against the robot's largest (gravity's, gravityWeight, and what is derived from
  /// a kept direction, that direction's singular value: see Span in recursive_base.cpp),
  /// smallest of those kept and largest of those dropped.
  double smallest_kept = 1.0;
  double largest_dropped = 0.0;
};

/// Why the recursive method cannot take `model` in `layout` (rotor inertia of a motor that
/// turns with two joints whose coupled energy it cannot prove independent of the links', see
/// recursive_base.cpp), or an empty string when it can.
std::string recursiveRefusal(const Model& model, ParameterLayout layout, double tolerance);

/// The identifiable space of `model` in `layout`; throws ModelError with recursiveRefusal's
/// reason when it refuses. `tolerance`: relative size below which a
/// vector counts as lying in a span (the recursion's own rank decisions, on spans of at most ten
/// dimensions).
IdentifiableSpace recursiveIdentifiable(const Model& model, ParameterLayout layout,
                                        double tolerance);

}  // namespace mindyn
