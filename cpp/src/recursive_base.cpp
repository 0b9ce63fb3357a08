#include "mindyn/recursive_base.hpp"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>

#include "mindyn/spatial.hpp"

namespace mindyn {

namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Vec10 = Eigen::Matrix<double, 10, 1>;
using Row10 = Eigen::Matrix<double, 1, 10>;
using Mat10 = Eigen::Matrix<double, 10, 10>;
// Up to ten rows of ten, on the stack.
using Rows10 = Eigen::Matrix<double, Eigen::Dynamic, 10, Eigen::RowMajor, 10, 10>;

// The ten parameters as inertia tensor about the frame origin, first moment and mass.
struct Parts {
  Eigen::Matrix3d I;
  Eigen::Vector3d h;
  double m;
};

Parts parts(const Vec10& p) {
  Parts s;
  s.I << p[0], p[1], p[2], p[1], p[3], p[4], p[2], p[4], p[5];
  s.h = p.segment<3>(6);
  s.m = p[9];
  return s;
}

Vec10 pack(const Parts& s) {
  Vec10 p;
  p << s.I(0, 0), s.I(0, 1), s.I(0, 2), s.I(1, 1), s.I(1, 2), s.I(2, 2), s.h, s.m;
  return p;
}

// The matrix of a linear map of the ten parameters, column by column.
template <class F>
Mat10 matrixOf(F f) {
  Mat10 M;
  for (int c = 0; c < 10; ++c) M.col(c) = f(parts(Vec10::Unit(c)));
  return M;
}

// Parameters of a body given in frame B expressed in frame A, B at rotation R and origin p in A:
// I_A = R I R^T + [p]x^T [R h]x + [R h]x^T [p]x + m [p]x^T [p]x, h_A = R h + m p.
Mat10 transformParameters(const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d R = T.linear(), P = skew(T.translation());
  return matrixOf([&](const Parts& s) {
    const Eigen::Matrix3d H = skew(R * s.h);
    return pack(
        {R * s.I * R.transpose() + P.transpose() * H + H.transpose() * P + s.m * P.transpose() * P,
         R * s.h + s.m * T.translation(), s.m});
  });
}

// Rate of change of the parameters of a body moving with the twist (w, v) (v: velocity of the
// point at the origin), seen from a frame momentarily coinciding with its own.
Mat10 parameterRate(const Vec6& S) {
  const Eigen::Matrix3d W = skew(S.head<3>()), V = skew(S.tail<3>());
  return matrixOf([&](const Parts& s) {
    const Eigen::Matrix3d H = skew(s.h);
    return pack({W * s.I - s.I * W + V.transpose() * H + H.transpose() * V,
                 S.head<3>().cross(s.h) + s.m * S.tail<3>(), 0.0});
  });
}

// The row c with c pi = a^T I(pi) b, I the spatial inertia about the origin:
// a^T I b = a_w^T I b_w + h . (b_v x a_w) + h . (a_v x b_w) + m a_v . b_v.
Row10 outputRow(const Vec6& a, const Vec6& b) {
  const Eigen::Vector3d aw = a.head<3>(), av = a.tail<3>(), bw = b.head<3>(), bv = b.tail<3>();
  Row10 c;
  c << aw.x() * bw.x(), aw.x() * bw.y() + aw.y() * bw.x(), aw.x() * bw.z() + aw.z() * bw.x(),
      aw.y() * bw.y(), aw.y() * bw.z() + aw.z() * bw.y(), aw.z() * bw.z(),
      (bv.cross(aw) + av.cross(bw)).transpose(), av.dot(bv);
  return c;
}

// Motion vectors of frame A expressed in frame B, B at (R, p) in A.
Vec6 motionToChild(const Eigen::Isometry3d& T, const Vec6& v) {
  const Eigen::Matrix3d Rt = T.linear().transpose();
  Vec6 out;
  out.head<3>() = Rt * v.head<3>();
  out.tail<3>() = Rt * (v.tail<3>() + v.head<3>().cross(T.translation()));
  return out;
}

// A span given by weighted vectors, each the vector divided by the size of what produced it and
// multiplied by the size of the torques it stands for, relative to the robot's largest in the
// unit-length model: 1 for a joint's motion, gravity's (gravityWeight) for gravity, and for what
// is derived from a direction of a span, that direction's size. The span's directions and their
// sizes are the left singular vectors and singular values of the matrix of its weighted vectors
// (kept compressed as Q diag(weight), D columns: the same singular values and vectors as all the
// vectors offered), a size at most that of the largest vector offered (a direction that several
// vectors share stands for torques no larger than the largest of them); a direction counts when
// its size exceeds the tolerance. A span closed under a map (a joint's motion) is offered the
// powers of the map on its vectors until one adds no direction: it is then closed. The decisions
// are thus the echelon form's "numerically zero" of the other methods: below the tolerance against
// the size of the robot's torques. They do not depend on the order in which the vectors come,
// and a direction is measured by everything that points along it: one that only the 3.7e-6 by
// which two nearly parallel axes differ sets apart keeps that size, and what the links' inertia
// shows of it, and what it moves in turn, is measured at that size and not at full size, as the
// regressor's columns are in the other methods (the rows of a link's inertia that only the
// square of the difference reveals, 1.3e-11 of the torques, are below the tolerance there too).
// A direction's rounding (the 6e-17 of a written right angle beside a motion of 1e-8) stays at
// its size: the singular vectors of the small singular values carry it relative to the gap
// between them, and times their size it is again at the rounding level of the whole.
struct Margin {
  double kept = 1.0, dropped = 0.0;
};

template <int D>
struct Span {
  using Block = Eigen::Matrix<double, D, Eigen::Dynamic, Eigen::ColMajor, D, 3 * D>;
  Eigen::Matrix<double, D, D> Q = Eigen::Matrix<double, D, D>::Zero();  // by size, largest first
  Eigen::Matrix<double, D, 1> weight = Eigen::Matrix<double, D, 1>::Zero();  // of each column
  int dim = 0;         // the columns over the tolerance
  double largest = 0;  // the size of the largest vector offered
  double tol;
  Margin* margin;
  Span(double tolerance, Margin& m) : tol(tolerance), margin(&m) {}
  // Offers weighted vectors (at most 2D at once).
  void add(const Block& W) {
    if (W.cols() == 0) return;
    Block G(D, D + W.cols());
    G << Q * weight.asDiagonal(), W;
    const Eigen::JacobiSVD<Block> svd(G, Eigen::ComputeFullU);
    Q = svd.matrixU();
    // (what several vectors put along a direction counts at most at the size of the largest:
    // sizes do not grow from link to link)
    largest = std::max(largest, W.colwise().norm().maxCoeff());
    weight = svd.singularValues().head(D).cwiseMin(largest);
    dim = 0;
    while (dim < D && weight[dim] > tol) ++dim;
  }
  // Offers the weighted vectors W and f(W), f(f(W)) .. (f of a weighted vector: the weighted
  // vector of what it produces) until a power adds no direction: the span closed under f.
  template <class F>
  void close(Block W, F f) {
    add(W);
    for (int power = 1, before = -1; power < D && dim > before; ++power) {
      before = dim;
      for (int c = 0; c < W.cols(); ++c) W.col(c) = f(W.col(c));
      add(W);
    }
  }
  // The decision is taken: its margins join the recursion's.
  void decide() const {
    if (dim > 0) margin->kept = std::min(margin->kept, weight[dim - 1]);
    if (dim < D) margin->dropped = std::max(margin->dropped, weight[dim]);
  }
  auto basis() const { return Q.leftCols(dim); }
  // The kept directions, each at its size.
  Block kept() const { return Q.leftCols(dim) * weight.head(dim).asDiagonal(); }
};

// The weight of gravity's motion directions: in the unit-length model (time in sqrt(L / 1 m) s,
// joint accelerations of order one) gravity weighs |g| against a joint's unit acceleration, and
// the torques it exerts are |g| s_k on joint k, s_k the sine of the angle between a revolute
// axis and the vertical (the cosine for a prismatic one) at q = 0: the weight is |g| relative to
// the largest torques, max(1, |g| max_k s_k). On a robot whose joints are all vertical but one
// tilted 1e-9 rad, gravity's torques on that joint are |g| 1e-9 of the inertial ones (weight
// |g|, as in the regressor); on an arm that gravity loads, its rows are the largest and a
// gravity direction counts at its own size (weight about 1).
double gravityWeight(const Model& model) {
  const double g = model.gravity.norm();
  if (!(g > 0)) return 1.0;
  const Eigen::Vector3d down = model.gravity / g;
  const int n = model.nq();
  std::vector<Eigen::Matrix3d> R(n);  // link k in the base at q = 0
  double largest = 0;
  for (int k = 0; k < n; ++k) {
    const Joint& joint = model.joints[k];
    const int p = model.parent(k);
    const Eigen::Matrix3d Rp = p < 0 ? Eigen::Matrix3d::Identity() : R[p];
    const Eigen::Vector3d u = Rp * joint.pre.linear() * joint.axis;
    largest = std::max(
        largest, joint.type == JointType::Revolute ? u.cross(down).norm() : std::abs(u.dot(down)));
    R[k] = Rp * joint.pre.linear() * joint.post.linear();
  }
  return g / std::max(1.0, g * largest);
}

// Motion subspace of joint k in link k's frame: rotation about the axis through the joint
// frame's origin, or translation along it.
Vec6 motionSubspace(const Joint& j) {
  const Eigen::Matrix3d Rt = j.post.linear().transpose();
  const Eigen::Vector3d u = Rt * j.axis;
  Vec6 S;
  if (j.type == JointType::Revolute) {
    const Eigen::Vector3d c = -(Rt * j.post.translation());  // a point of the axis
    S << u, c.cross(u);
  } else {
    S << Eigen::Vector3d::Zero(), u;
  }
  return S;
}

}  // namespace

IdentifiableSpace recursiveIdentifiable(const Model& model, ParameterLayout layout,
                                        double tolerance) {
  requireSingleDof(model, "the recursive method");
  model.validate();
  if (const std::string why = recursiveRefusal(model, layout, tolerance); !why.empty())
    throw ModelError(why);
  const int n = model.nq(), P = layout.size(n), per = layout.perLink();
  IdentifiableSpace out;
  out.link_rank.resize(n);
  Margin margin;

  // Motion span of the fixed base (gravity as its acceleration) and of each link, and the rows
  // spanning what is identifiable of each link's inertia (nothing of the base's).
  Span<6> Vbase(tolerance, margin);
  if (model.gravity.norm() > 0) {
    Vec6 g;
    g << Eigen::Vector3d::Zero(), -model.gravity;
    Vbase.add(g / g.norm() * gravityWeight(model));
  }
  Vbase.decide();
  const Span<10> Cbase(tolerance, margin);
  std::vector<Span<6>> Vs(n, Span<6>(tolerance, margin));
  std::vector<Span<10>> Cs(n, Span<10>(tolerance, margin));
  std::vector<Mat10> T0(n);
  std::vector<Rows10> M(n);      // basis of N_k
  std::vector<Rows10> rotor(n);  // x0 of a regrouped rotor
  for (int k = 0; k < n; ++k) {
    const Joint& joint = model.joints[k];
    const int p = model.parent(k);
    const Span<6>& Vp = p < 0 ? Vbase : Vs[p];
    const Span<10>& Cp = p < 0 ? Cbase : Cs[p];
    const Eigen::Isometry3d X = joint.pre * joint.post;  // link k in its parent link at q_k = 0
    const Vec6 S = motionSubspace(joint);
    const double sn = S.norm();
    T0[k] = transformParameters(X);

    // Rotor inertia: tau_k += Ia q''_k equals the torques of the inertia u u^T on link k when the
    // parent link does not rotate about axes with a component along u. Prismatic: those of a unit
    // mass on link k less one on the parent link, when the parent link moves in planes normal to
    // u (gravity included): its rotations about axes along u, its translations normal to u. A
    // unit point mass at a point of link k and one at the same point of the parent link at
    // q_k = 0 then differ in kinetic energy by q'_k^2 / 2 and not in potential energy; when the
    // parent link does not rotate, the one on the parent link may sit at its origin. Otherwise
    // the rotor's column is taken as independent of all others: a sufficient condition only,
    // which the tests check against the projection method and the sampled regressor (bundled and
    // random arms and trees, mixed joints).
    if (layout.rotor) {
      const Eigen::Vector3d u = joint.pre.linear() * joint.axis;  // in the parent link
      bool decoupled = true, still = true;
      for (int i = 0; i < Vp.dim; ++i) {
        const Vec6 v = Vp.Q.col(i) * Vp.weight[i];  // (weighted as the spans' decisions)
        const Eigen::Vector3d w = v.head<3>();
        if (joint.type == JointType::Revolute) {
          decoupled = decoupled && std::abs(u.dot(w)) <= tolerance;
        } else {
          still = still && w.norm() <= tolerance;
          decoupled = decoupled && (w - u.dot(w) * u).norm() <= tolerance &&
                      std::abs(u.dot(v.tail<3>())) <= tolerance;
        }
      }
      if (decoupled) {
        rotor[k].setZero(p >= 0 && joint.type == JointType::Prismatic ? 2 : 1, 10);
        if (joint.type == JointType::Revolute) {
          const Eigen::Vector3d w = S.head<3>();
          Parts s{w * w.transpose(), Eigen::Vector3d::Zero(), 0.0};
          rotor[k].row(0) = pack(s).transpose();
        } else {
          rotor[k](0, 9) = 1.0;  // unit mass at the origin of link k
          if (p >= 0 && still)
            rotor[k](1, 9) = -1.0;  // less one at the origin of the parent link
          else if (p >= 0)          // less one where link k's origin is at q_k = 0
            rotor[k].row(1) = -T0[k].col(9).transpose();
        }
      }
    }

    // V_k: the motions of the parent link seen from link k, and S_k, closed under joint k's
    // motion.
    Span<6>& V = Vs[k];
    Span<6>::Block W(6, 1 + Vp.dim);
    W.col(0) = S / sn;
    int cols = 1;
    for (int i = 0; i < Vp.dim; ++i) {
      const Vec6 v = motionToChild(X, Vp.Q.col(i));
      if (v.norm() > 0) W.col(cols++) = v / v.norm() * Vp.weight[i];
    }
    V.close(W.leftCols(cols), [&](const Vec6& v) -> Vec6 { return crossMotion(S, v) / sn; });
    V.decide();

    // O_k: what the parent link identifies of link k's inertia, at every q_k (closed under the
    // rate).
    const Mat10 At = parameterRate(S).transpose();
    const double an = At.norm();
    Span<10>::Block R(10, Cp.dim);
    cols = 0;
    for (int i = 0; i < Cp.dim; ++i) {
      const Vec10 r = T0[k].transpose().lazyProduct(Cp.Q.col(i));
      if (r.norm() > 0) R.col(cols++) = r / r.norm() * Cp.weight[i];
    }
    Span<10> O(tolerance, margin);
    O.close(R.leftCols(cols), [&](const Vec10& r) -> Vec10 { return At * r / an; });
    O.decide();

    // N_k: s^T I v for v in V_k, and the rates of O_k.
    Span<10> N(tolerance, margin);
    Span<10>::Block outputs(10, V.dim);
    for (int i = 0; i < V.dim; ++i)
      outputs.col(i) = outputRow(S, V.Q.col(i)).transpose() / sn * V.weight[i];
    N.add(outputs);
    N.add(At * O.kept() / an);
    N.decide();
    M[k] = N.basis().transpose();
    out.link_rank[k] = N.dim;

    // C_k: what the parent link identifies of link k at q_k = 0, and N_k.
    Span<10>& C = Cs[k];
    C.add(R.leftCols(cols));
    C.add(N.kept());
    C.decide();
  }

  out.smallest_kept = margin.kept;
  out.largest_dropped = margin.dropped;

  // The rows: per link j, its N_j basis on link j and carried outwards over its subtree,
  // n T_{j,k} = (n T_{j,parent(k)}) T0_k; then the rotor inertia (its own row, or the value of the
  // rows on its regrouping vector) and friction.
  // On the motor side (Model::motorSide), motor m's rotor energy 1/2 Ia_m (t_m . dq)^2 is
  //   Ia_m [ sum_a t_ma^2 (1/2 dq_a^2) + sum_{a > b} t_ma t_mb (dq_a dq_b) ]:
  // its column is sum_a t_ma^2 D_a + sum_{a > b} t_ma t_mb E_ab, with D_a the column of a
  // joint-side rotor inertia of joint a and E_ab that of the energy dq_a dq_b. The rows of the
  // columns (links, D, E) give those of (links, Ia) by that same combination (a linear map of
  // columns keeps the rows spanning the identifiable space). D_a is taken as above. E_ab is a
  // column of its own (an own row) when no link's kinetic energy has a constant coefficient on
  // dq_a dq_b: always when a and b are on different root paths; for b an ancestor of a when the
  // motion of joint b seen from link a averages out over the joints in between (the mean of a
  // rotation about u is u u^T; a prismatic joint counts at zero travel), since that coefficient
  // is the mean motion of joint b times the links' inertia times S_a. Otherwise E_ab may regroup
  // with the links, which the recursion cannot decide: recursiveRefusal says so.
  const bool motors = layout.rotor && model.motorSide();
  const Eigen::MatrixXd& Tm = model.transmission.T;
  // Adds `v` (rows r .. r + size) for a joint-side column of joint a: to each motor's column.
  auto rotorEntries = [&](int r, int a, const Eigen::VectorXd& v,
                          std::vector<Eigen::Triplet<double>>& entries) {
    for (int m = 0; m < (motors ? n : 1); ++m) {
      const double c = motors ? Tm(m, a) * Tm(m, a) : 1.0;
      const int col = layout.rotorIndex(motors ? m : a);
      if (c == 0.0) continue;
      for (int i = 0; i < v.size(); ++i)
        if (v[i] != 0.0) entries.emplace_back(r + i, col, c * v[i]);
    }
  };
  std::vector<std::pair<int, int>> pairs;  // (a, b), a > b, coupled by some motor
  for (int a = 0; a < n && motors; ++a)
    for (int b = 0; b < a; ++b)
      for (int m = 0; m < n; ++m)
        if (Tm(m, a) != 0.0 && Tm(m, b) != 0.0) {
          pairs.emplace_back(a, b);
          break;
        }
  int rows = static_cast<int>(pairs.size());
  for (int k = 0; k < n; ++k) {
    rows += out.link_rank[k];
    if (layout.rotor && rotor[k].rows() == 0) ++rows;
    if (layout.friction) rows += layout.friction_columns;
  }
  // The rows are sparse: those of link j are zero outside the columns of its subtree, whose
  // total size grows as n log n on a random tree (as n^2 only on a long chain).
  std::vector<Eigen::Triplet<double>> entries;
  std::vector<char> below(n);      // link k in the subtree of link j
  std::vector<Rows10> carried(n);  // n T_{j,k}
  auto put = [&](int r, int col, const Eigen::Ref<const Eigen::VectorXd>& v) {
    for (int i = 0; i < v.size(); ++i)
      if (v[i] != 0.0) entries.emplace_back(r + i, col, v[i]);
  };
  int r0 = 0;
  for (int j = 0; j < n; ++j) {
    const int nj = out.link_rank[j];
    for (int k = j; k < n; ++k) {
      const int p = model.parent(k);
      below[k] = k == j || (p >= j && below[p]);
      if (!below[k]) continue;
      if (k == j)
        carried[k] = M[j];
      else
        carried[k].noalias() = carried[p].lazyProduct(T0[k]);
      for (int c = 0; c < 10; ++c) put(r0, k * per + c, carried[k].col(c));
      // A regrouped rotor's column: the value of the rows on its regrouping vector (on link k,
      // and on its parent link when that is in the subtree too).
      if (layout.rotor && rotor[k].rows() > 0) {
        Eigen::VectorXd v = carried[k] * rotor[k].row(0).transpose();
        if (rotor[k].rows() > 1 && k != j) v += carried[p] * rotor[k].row(1).transpose();
        rotorEntries(r0, k, v, entries);
      }
    }
    r0 += nj;
    if (layout.rotor && rotor[j].rows() == 0)
      rotorEntries(r0++, j, Eigen::VectorXd::Ones(1), entries);
    for (int i = 0; layout.friction && i < layout.friction_columns; ++i)
      entries.emplace_back(r0++, layout.frictionIndex(j, i), 1.0);
  }
  for (const auto& [a, b] : pairs) {  // E_ab, its own row
    for (int m = 0; m < n; ++m)
      if (Tm(m, a) != 0.0 && Tm(m, b) != 0.0)
        entries.emplace_back(r0, layout.rotorIndex(m), Tm(m, a) * Tm(m, b));
    ++r0;
  }
  for (int k = 0; k < n && layout.rotor; ++k)
    if (rotor[k].rows() > 0) out.rotor_regrouped.push_back(k);
  out.rows.resize(rows, P);
  out.rows.setFromTriplets(entries.begin(), entries.end());

  // The constant of the Lagrangian: the potential energy's mean over the revolute joints (the
  // pose is affine in each joint's cos and sin, one joint per factor, so the mean of the product
  // is the product of the means; a rotation's mean is u u^T) and its value at q = 0 for the
  // prismatic ones.
  out.constant.setZero(P);
  std::vector<Eigen::Matrix4d> T(n);
  for (int k = 0; k < n; ++k) {
    const Joint& joint = model.joints[k];
    const int p = model.parent(k);
    Eigen::Matrix4d J = Eigen::Matrix4d::Identity();
    if (joint.type == JointType::Revolute)
      J.topLeftCorner<3, 3>() = joint.axis * joint.axis.transpose();
    T[k] = (p >= 0 ? T[p] : Eigen::Matrix4d::Identity()) * joint.pre.matrix() * J *
           joint.post.matrix();
    out.constant.segment<3>(k * per + 6) = model.gravity.transpose() * T[k].topLeftCorner<3, 3>();
    out.constant[k * per + 9] = model.gravity.dot(T[k].block<3, 1>(0, 3));
  }
  return out;
}

std::string recursiveRefusal(const Model& model, ParameterLayout layout, double tolerance) {
  // A multi-DOF joint: the method runs on the single-DOF expansion (expandToSingleDof), whose
  // joints have no rotor inertia.
  if (!model.singleDof()) return "";
  if (!layout.rotor || !model.motorSide() || model.transmission.nm() != model.nq()) return "";
  const int n = model.nq();
  const Eigen::MatrixXd& T = model.transmission.T;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < a; ++b) {
      int motor = -1;
      for (int m = 0; m < n && motor < 0; ++m)
        if (T(m, a) != 0.0 && T(m, b) != 0.0) motor = m;
      if (motor < 0) continue;
      // The mean motion of joint b seen from link a (b an ancestor of a), or none.
      int c = a;
      std::vector<int> path;
      while (c >= 0 && c != b) {
        path.push_back(c);
        c = model.parent(c);
      }
      if (c != b) continue;  // different root paths
      Vec6 v = motionSubspace(model.joints[b]);
      const double size = v.norm();
      for (auto it = path.rbegin(); it != path.rend(); ++it) {
        const Joint& joint = model.joints[*it];
        v = motionToChild(joint.pre, v);
        if (joint.type == JointType::Revolute) {
          const Eigen::Matrix3d P = joint.axis * joint.axis.transpose();
          v.head<3>() = P * v.head<3>();
          v.tail<3>() = P * v.tail<3>();
        }
        v = motionToChild(joint.post, v);
      }
      if (v.norm() <= tolerance * size) continue;
      return "the recursive method cannot decide whether the rotor inertia of motor '" +
             model.transmission.motors[motor] + "', which turns with joints '" +
             model.joints[b].name + "' and '" + model.joints[a].name +
             "', regroups with the links (the motion of the first does not average out as seen "
             "from the second); the projection and numerical methods can";
    }
  return "";
}

}  // namespace mindyn
