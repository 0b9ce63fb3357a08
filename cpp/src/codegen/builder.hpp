// The symbolic Newton-Euler recursion on the stages of every joint (stages.hpp), written into
// an expression graph, on a chain or a tree (Model::parent). Forward, from the parent's link:
// angular velocity and acceleration and the linear acceleration of each stage origin (gravity as
// an upward base acceleration), in the axes of that stage. Backward: the wrench (moment about the
// stage origin, force), carried as pending linear forms in the parameters while only sums and
// signed permutations act on it, each link's added to its parent's; the torque is the axis
// component of the moment (revolute) or of the force (prismatic) right after the joint motion.
// A link's wrench is formed in its own frame or in the joint frame before the joint motion
// (LinkForm), with its parameters turned by the joint angle.
//
// A floating base: a free-flyer or planar joint on the fixed base moves its link by its velocity
// and acceleration inputs (rootForward), gravity turned into the link's axes by the joint's
// rotation; its generalised forces are the components of the wrench in the moved frame. Contact
// wrenches (setContacts) are subtracted from their links' wrenches, turned from world axes down
// the joints when given in world axes.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include "drive_terms.hpp"
#include "mindyn/codegen/expr.hpp"
#include "mindyn/model.hpp"
#include "stages.hpp"

namespace mindyn::codegen::internal {

using V3 = std::array<Ref, 3>;
using M3 = std::array<V3, 3>;     // rows
using P10 = std::array<Ref, 10>;  // XX XY XZ YY YZ ZZ MX MY MZ M
using Sym3 = std::array<std::array<int, 3>, 3>;

// The inertial parameters of a body as the wrench recursion uses them: the inertia tensor as a
// sum of parameters times constant symmetric tensors, the first moment and the mass.
struct Body {
  std::vector<std::pair<Ref, Sym3>> inertia;
  V3 ms;
  Ref mass;
};

struct Motion {
  V3 w, dw, a;  // angular velocity, angular acceleration, linear acceleration of the origin
  // Set for a link seen in its joint frame before the joint motion, the joint turning about
  // coordinate axis `axis`: the parent's angular velocity and acceleration in the same axes,
  // of which w and dw are these plus the joint terms.
  int axis = -1;
  V3 wp{}, dwp{};
};

// A wrench component not yet written as a node: the sum of `rest` and of the products of the
// kinematic coefficients and parameters in `terms` (coefficient, parameter).
struct Component {
  std::vector<std::pair<Ref, Ref>> terms;
  Ref rest;
};

struct Pending {
  std::array<Component, 3> n, f;  // moment about the origin, force
};

class Builder {
 public:
  Builder(Graph& g, const Model& model, std::vector<JointStages> stages)
      : g_(g), model_(model), stages_(std::move(stages)) {
    zero_ = {Graph::zero(), Graph::zero(), Graph::zero()};
    gravity_ = cleanGeometry<3, 1>(model.gravity, false, nullptr);
    for (int k = 0, i = 0, j = 0; k < model.nq(); ++k) {
      iq_.push_back(i);
      iv_.push_back(j);
      i += model.joints[k].nq();
      j += model.joints[k].nv();
    }
  }

  // The links that receive a contact wrench in the inverse dynamics: link `links[c]` (the link
  // joint links[c] moves) the wrench f[6 c .. 6 c + 5] (force, moment about the link's origin)
  // in world axes (`world`) or in the link's axes; it is subtracted from the link's wrench.
  void setContacts(const std::vector<int>& links, bool world) {
    contacts_ = links;
    contactWorld_ = world;
  }

  // Forward pass: fills the joint trigonometry and the motion of every link frame. dq and ddq
  // have an entry per velocity coordinate (one per joint on a model of single-DOF joints).
  void forward(const std::vector<Ref>& dq, const std::vector<Ref>& ddq, bool gravity) {
    const int n = model_.nq();
    rootR_.assign(n, M3{});
    quat_.assign(n, M3{});
    q_.assign(n, Graph::zero());
    jointR_.assign(n, M3{});
    jointC_.assign(n, Graph::one());
    jointS_.assign(n, Graph::zero());
    link_.assign(n, Motion{});
    linkPre_.assign(n, Motion{});
    afterA_.assign(n, V3{});
    dq_ = dq;
    ddq_ = ddq;
    Motion base{zero_, zero_, zero_};
    if (gravity)
      for (int i = 0; i < 3; ++i) base.a[i] = g_.constant(-gravity_[i]);
    for (int k = 0; k < n; ++k) {
      const JointStages& s = stages_[k];
      const int parent = model_.parent(k);
      Motion m = rigidForward(s.pre, parent < 0 ? base : link_[parent]);
      if (isRoot(s.type)) {
        // on the fixed base (checkCodegenJoints): m.a is the gravity term, w and dw are zero
        link_[k] = rigidForward(s.post, rootForward(k, m.a, dq, ddq));
        continue;
      }
      const Ref qk = g_.input(InputKind::Q, iq_[k]);
      const V3 u = constVec(s.u);
      if (s.type == JointType::Revolute) {
        const Ref angle = g_.add(qk, g_.constant(s.offset));
        const Ref c = g_.cos(angle), sn = g_.sin(angle);
        jointC_[k] = c;
        jointS_[k] = sn;
        jointR_[k] = rodrigues(s.u, c, sn);
        const V3 wj = scale(u, dq[iv_[k]]);
        // the link's motion in the joint frame before the joint motion (same origin)
        linkPre_[k] = {addv(m.w, wj), addv(addv(m.dw, scale(u, ddq[iv_[k]])), cross(m.w, wj)), m.a};
        for (int i = 0; i < 3; ++i)
          if (std::abs(s.u[i]) == 1.0) linkPre_[k].axis = i;
        linkPre_[k].wp = m.w;
        linkPre_[k].dwp = m.dw;
        const V3 wr = mulT(jointR_[k], m.w);
        m.w = addv(wr, wj);
        m.dw = addv(addv(mulT(jointR_[k], m.dw), scale(u, ddq[iv_[k]])), cross(wr, wj));
        m.a = mulT(jointR_[k], m.a);
      } else {
        q_[k] = qk;
        const V3 d = scale(u, qk);
        // a' = a + U d + 2 w x (u dq) + u ddq
        V3 a = addv(m.a, uTimes(m, d));
        a = addv(a, scale(cross(m.w, scale(u, dq[iv_[k]])), g_.constant(2.0)));
        m.a = addv(a, scale(u, ddq[iv_[k]]));
      }
      afterA_[k] = m.a;
      m = rigidForward(s.post, m);
      link_[k] = m;
    }
  }

  // Backward pass for a classical parameter vector (layout of the model's ParameterSet).
  // `forms[k]` (see LinkForm): link k's wrench is formed in its own frame, or in the joint frame
  // before the joint motion from its parameters carried into that frame. The wrench is carried as
  // pending linear forms in the parameters for as long as only sums and signed permutations act on
  // it, so that equal kinematic coefficients of different links share one product. Each link's
  // total wrench (its own and its descendants') is carried into its parent's link frame and added
  // to the parent's; children come after their parent, so all of them are in when it is reached.
  std::vector<Ref> torques(const std::vector<Ref>& pi, ParameterLayout layout, bool joint_terms,
                           const std::vector<LinkForm>& forms) {
    const int n = model_.nq();
    std::vector<Ref> tau(model_.velocitySize(), Graph::zero());
    std::vector<Pending> children(n);  // the children's wrenches in each link's frame
    for (int k = n - 1; k >= 0; --k) {
      const JointStages& s = stages_[k];
      Pending w = std::move(children[k]);
      P10 own;
      for (int i = 0; i < 10; ++i) own[i] = pi[k * layout.perLink() + i];
      const LinkForm form = forms[k];
      const bool pre = form.frame != 0 && s.type == JointType::Revolute;
      if (!pre) append(w, linkWrench(link_[k], body(own)));
      for (size_t c = 0; c < contacts_.size(); ++c)
        if (contacts_[c] == k) append(w, contactWrench(k, static_cast<int>(c)));
      w = rigidBackward(s.post, w);
      if (isRoot(s.type)) {  // on the fixed base: no parent
        // tau of a free-flyer: (force; moment) in the moved frame; of a planar joint fx, fy, nz
        const int iv = iv_[k];
        if (s.type == JointType::FreeFlyer) {
          for (int i = 0; i < 3; ++i) tau[iv + i] = value(w.f[i]);
          for (int i = 0; i < 3; ++i) tau[iv + 3 + i] = value(w.n[i]);
        } else {
          tau[iv] = value(w.f[0]);
          tau[iv + 1] = value(w.f[1]);
          tau[iv + 2] = value(w.n[2]);
        }
        continue;
      }
      const V3 u = constVec(s.u);
      Ref t;
      if (s.type == JointType::Revolute) {
        const M3& R = jointR_[k];
        w.n = rotate(R, w.n);
        w.f = rotate(R, w.f);
        if (pre) {
          const P10 after = transformParams(s.post, own);
          const Body turned = rotateParams(s.u, jointC_[k], jointS_[k], after, form.frame);
          append(w, linkWrench(linkPre_[k], turned, !form.momentAfter));
          if (form.momentAfter) {
            std::array<Component, 3> m;
            const V3 v = cross({after[6], after[7], after[8]}, afterA_[k]);
            for (int i = 0; i < 3; ++i) m[i].rest = v[i];
            m = rotate(R, m);
            for (int i = 0; i < 3; ++i) w.n[i].rest = g_.add(w.n[i].rest, m[i].rest);
          }
        }
        t = along(u, w.n);  // the axis is the same before and after the joint motion
      } else {
        t = along(u, w.f);
        const V3 extra = cross(scale(u, q_[k]), values(w.f));
        for (int i = 0; i < 3; ++i) w.n[i].rest = g_.add(value(w.n[i]), extra[i]);
      }
      tau[iv_[k]] = t;
      const int parent = model_.parent(k);
      if (parent < 0) continue;
      append(children[parent], rigidBackward(s.pre, std::move(w)));
    }
    if (joint_terms) addDriveTerms(g_, model_, pi, layout, ddq_, tau, dq_, tau);
    return tau;
  }

 protected:
  // A spatial vector in a link frame: a motion (angular velocity, linear velocity of the origin)
  // or a force (moment about the origin, force).
  struct SV {
    V3 w, l;
  };

  static bool isRoot(JointType t) { return t == JointType::FreeFlyer || t == JointType::Planar; }

  // The motion of the frame moved by root joint k (a free-flyer or planar joint on the fixed
  // base), in its axes, from its velocity and acceleration coordinates (linear first, as
  // Pinocchio's; a free-flyer's acceleration is the derivative of its body velocity, whose
  // origin then accelerates by al + w x vl) and `g`, the base's upward acceleration in the joint
  // frame. Fills rootR_[k], the joint's rotation.
  Motion rootForward(int k, const V3& g, const std::vector<Ref>& dq, const std::vector<Ref>& ddq) {
    const int iq = iq_[k], iv = iv_[k];
    const JointType type = model_.joints[k].type;
    V3 vl, al;
    Motion m;
    if (type == JointType::FreeFlyer) {
      const Ref x = g_.input(InputKind::Q, iq + 3), y = g_.input(InputKind::Q, iq + 4),
                z = g_.input(InputKind::Q, iq + 5), w = g_.input(InputKind::Q, iq + 6);
      // R = 1 + 2 S (a unit quaternion x, y, z, w), S as below
      quat_[k] = {V3{-g_.add(g_.mul(y, y), g_.mul(z, z)), g_.sub(g_.mul(x, y), g_.mul(z, w)),
                     g_.add(g_.mul(x, z), g_.mul(y, w))},
                  V3{g_.add(g_.mul(x, y), g_.mul(z, w)), -g_.add(g_.mul(x, x), g_.mul(z, z)),
                     g_.sub(g_.mul(y, z), g_.mul(x, w))},
                  V3{g_.sub(g_.mul(x, z), g_.mul(y, w)), g_.add(g_.mul(y, z), g_.mul(x, w)),
                     -g_.add(g_.mul(x, x), g_.mul(y, y))}};
      const Ref two = g_.constant(2.0);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          rootR_[k][i][j] = g_.mul(two, quat_[k][i][j]);
          if (i == j) rootR_[k][i][j] = g_.add(Graph::one(), rootR_[k][i][j]);
        }
      vl = {dq[iv], dq[iv + 1], dq[iv + 2]};
      al = {ddq[iv], ddq[iv + 1], ddq[iv + 2]};
      m.w = {dq[iv + 3], dq[iv + 4], dq[iv + 5]};
      m.dw = {ddq[iv + 3], ddq[iv + 4], ddq[iv + 5]};
    } else {  // planar: q = (x, y, cos t, sin t), v = (vx, vy, wz)
      const Ref c = g_.input(InputKind::Q, iq + 2), sn = g_.input(InputKind::Q, iq + 3);
      rootR_[k] = {V3{c, -sn, Graph::zero()}, V3{sn, c, Graph::zero()},
                   V3{Graph::zero(), Graph::zero(), Graph::one()}};
      vl = {dq[iv], dq[iv + 1], Graph::zero()};
      al = {ddq[iv], ddq[iv + 1], Graph::zero()};
      m.w = {Graph::zero(), Graph::zero(), dq[iv + 2]};
      m.dw = {Graph::zero(), Graph::zero(), ddq[iv + 2]};
    }
    m.a = addv(addv(al, cross(m.w, vl)), rootTurnBack(k, g));
    return m;
  }

  // R^T x for root joint k's rotation R. A free-flyer's R = 1 + 2 S: for a constant x (the
  // gravity term) x + S^T (2 x), whose constant factors fold.
  V3 rootTurnBack(int k, const V3& x) {
    if (model_.joints[k].type != JointType::FreeFlyer ||
        !(g_.isConstant(x[0]) && g_.isConstant(x[1]) && g_.isConstant(x[2])))
      return mulT(rootR_[k], x);
    V3 y = x;
    for (int i = 0; i < 3; ++i) {
      if (x[i] == Graph::zero()) continue;
      const Ref c = g_.constant(2.0 * g_.constantValue(x[i]));
      for (int j = 0; j < 3; ++j) y[j] = g_.add(y[j], g_.mul(c, quat_[k][i][j]));
    }
    return y;
  }

  // Minus contact c's wrench on link k, in link k's axes: a world-axes wrench is turned down the
  // joints from the base to the link (the rotations of each joint's constant transforms and of
  // its motion); the moment is about the link's origin in either axes.
  Pending contactWrench(int k, int c) {
    V3 n, f;
    for (int i = 0; i < 3; ++i) {
      f[i] = g_.input(InputKind::F, 6 * c + i);
      n[i] = g_.input(InputKind::F, 6 * c + 3 + i);
    }
    if (contactWorld_) {
      std::vector<int> path;
      for (int j = k; j >= 0; j = model_.parent(j)) path.push_back(j);
      for (auto it = path.rbegin(); it != path.rend(); ++it) {
        const JointStages& s = stages_[*it];
        auto turn = [&](const Rigid& T) {
          if (T.R.isIdentity(0.0)) return;
          const M3 R = constMat(T.R);
          n = mulT(R, n);
          f = mulT(R, f);
        };
        turn(s.pre);
        if (isRoot(s.type)) {
          n = rootTurnBack(*it, n);
          f = rootTurnBack(*it, f);
        } else if (s.type == JointType::Revolute) {
          n = mulT(jointR_[*it], n);
          f = mulT(jointR_[*it], f);
        }
        turn(s.post);
      }
    }
    Pending w;
    for (int i = 0; i < 3; ++i) {
      w.n[i].rest = -n[i];
      w.f[i].rest = -f[i];
    }
    return w;
  }

  Graph& graph() { return g_; }
  V3 subv(const V3& a, const V3& b) { return addv(a, {-b[0], -b[1], -b[2]}); }
  SV addsv(const SV& a, const SV& b) { return {addv(a.w, b.w), addv(a.l, b.l)}; }
  // Motion vector of the parent in the frame of a constant transform (x_parent = R x + t).
  SV toChild(const Rigid& T, const SV& x) {
    if (T.identity()) return x;
    const M3 R = constMat(T.R);
    const V3 l = T.t.isZero(0.0) ? x.l : addv(x.l, cross(x.w, constVec(T.t)));
    return {mulT(R, x.w), mulT(R, l)};
  }
  // Wrench (moment, force) in the parent frame of a constant transform.
  SV toParent(const Rigid& T, const SV& x) {
    if (T.identity()) return x;
    const M3 R = constMat(T.R);
    const V3 fp = mul(R, x.l);
    V3 np = mul(R, x.w);
    if (!T.t.isZero(0.0)) np = addv(np, cross(constVec(T.t), fp));
    return {np, fp};
  }
  // The spatial inertia about the origin applied to a motion vector: (I w + h x l, m l - h x w).
  SV inertia(const P10& p, const SV& x) {
    const M3 I = {V3{p[0], p[1], p[2]}, V3{p[1], p[3], p[4]}, V3{p[2], p[4], p[5]}};
    const V3 h = {p[6], p[7], p[8]};
    return {addv(mul(I, x.w), cross(h, x.l)), subv(scale(x.l, p[9]), cross(h, x.w))};
  }
  V3 constVec(const Eigen::Vector3d& v) {
    return {g_.constant(v[0]), g_.constant(v[1]), g_.constant(v[2])};
  }
  M3 constMat(const Eigen::Matrix3d& R) {
    M3 m;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m[i][j] = g_.constant(R(i, j));
    return m;
  }
  V3 addv(const V3& a, const V3& b) {
    return {g_.add(a[0], b[0]), g_.add(a[1], b[1]), g_.add(a[2], b[2])};
  }
  V3 scale(const V3& a, Ref s) { return {g_.mul(a[0], s), g_.mul(a[1], s), g_.mul(a[2], s)}; }
  Ref dot(const V3& a, const V3& b) {
    return g_.add(g_.add(g_.mul(a[0], b[0]), g_.mul(a[1], b[1])), g_.mul(a[2], b[2]));
  }
  V3 cross(const V3& a, const V3& b) {
    return {g_.sub(g_.mul(a[1], b[2]), g_.mul(a[2], b[1])),
            g_.sub(g_.mul(a[2], b[0]), g_.mul(a[0], b[2])),
            g_.sub(g_.mul(a[0], b[1]), g_.mul(a[1], b[0]))};
  }
  V3 mul(const M3& R, const V3& x) {
    V3 y;
    for (int i = 0; i < 3; ++i) y[i] = dot(R[i], x);
    return y;
  }
  V3 mulT(const M3& R, const V3& x) {
    V3 y;
    for (int i = 0; i < 3; ++i) y[i] = dot({R[0][i], R[1][i], R[2][i]}, x);
    return y;
  }
  // Rot(u, q) = (I + K^2) - cos q K^2 + sin q K, K = [u]x.
  M3 rodrigues(const Eigen::Vector3d& u, Ref c, Ref s) {
    Eigen::Matrix3d K;
    K << 0, -u.z(), u.y(), u.z(), 0, -u.x(), -u.y(), u.x(), 0;
    const Eigen::Matrix3d K2 = K * K;
    // derived from the (already cleaned) axis: only round-off is removed here
    const Eigen::Matrix3d A0 = (Eigen::Matrix3d::Identity() + K2).unaryExpr(&roundOffClean);
    const Eigen::Matrix3d A1 = (-K2).unaryExpr(&roundOffClean);
    M3 R;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        R[i][j] = g_.add(g_.add(g_.constant(A0(i, j)), g_.mul(g_.constant(A1(i, j)), c)),
                         g_.mul(g_.constant(K(i, j)), s));
    return R;
  }
  // dw_k + w_i w_j (plus) or dw_k - w_i w_j. In the frame before a joint turning about
  // coordinate axis a, with (b, d, a) right-handed, the joint terms cancel in two of these:
  // dw_b - w_d w_a = dwp_b - wp_d wp_a and dw_d + w_b w_a = dwp_d + wp_b wp_a, the same sums
  // as the parent's.
  Ref dwPlusWW(const Motion& m, int k, int i, int j, bool plus) {
    if (m.axis >= 0) {
      const int a = m.axis, b = (a + 1) % 3, d = (a + 2) % 3;
      const bool ia = i == a || j == a, ib = i == b || j == b, id = i == d || j == d;
      if (k == b && ia && id && !plus) return g_.sub(m.dwp[b], g_.mul(m.wp[d], m.wp[a]));
      if (k == d && ia && ib && plus) return g_.add(m.dwp[d], g_.mul(m.wp[b], m.wp[a]));
    }
    const Ref ww = g_.mul(m.w[i], m.w[j]);
    return plus ? g_.add(m.dw[k], ww) : g_.sub(m.dw[k], ww);
  }
  // Entry (i, j) of U = [dw]x + [w]x^2: w_i w_j + [dw]x(i, j), diagonal -(w_j^2 + w_k^2).
  Ref uEntry(const Motion& m, int i, int j) {
    if (i == j) {
      const int a = (i + 1) % 3, b = (i + 2) % 3;
      return -g_.add(g_.mul(m.w[a], m.w[a]), g_.mul(m.w[b], m.w[b]));
    }
    // [dw]x(i, j) = -eps_ijk dw_k
    const int k = 3 - i - j;
    const bool plus = (j == (i + 2) % 3);  // (0,2), (1,0), (2,1): +dw_k
    return plus ? dwPlusWW(m, k, i, j, true) : -dwPlusWW(m, k, i, j, false);
  }
  V3 uTimes(const Motion& m, const V3& d) {
    V3 y;
    for (int i = 0; i < 3; ++i) {
      Ref s = Graph::zero();
      for (int j = 0; j < 3; ++j)
        if (d[j] != Graph::zero()) s = g_.add(s, g_.mul(uEntry(m, i, j), d[j]));
      y[i] = s;
    }
    return y;
  }
  // Entry (i, j) of the inertia tensor in a parameter vector XX XY XZ YY YZ ZZ MX MY MZ M.
  static int tensorIndex(int i, int j) {
    static const int idx[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
    return idx[i][j];
  }

  // The body's tensor and first moment in axes turned by R (x_new = R x_old): R I R^T, R h; the
  // mass as it is.
  P10 turned(const M3& R, const P10& p) {
    M3 I;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) I[i][j] = p[tensorIndex(i, j)];
    M3 RI;
    for (int i = 0; i < 3; ++i) RI[i] = mulT(I, R[i]);  // row i of R I (I symmetric)
    P10 out = p;
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) out[tensorIndex(i, j)] = dot(RI[i], R[j]);
    const V3 h = mul(R, {p[6], p[7], p[8]});
    for (int i = 0; i < 3; ++i) out[6 + i] = h[i];
    return out;
  }

  // Parameters of a body about the origin of frame B, from those about the origin of frame A,
  // with x_B = R x_A + t: first moment R h + m t, inertia
  // R I R^T + 2 (t . R h) 1 - (R h) t^T - t (R h)^T + m (|t|^2 1 - t t^T).
  P10 transformParams(const Rigid& T, const P10& p) {
    if (T.identity()) return p;
    const M3 R = constMat(T.R);
    P10 out = turned(R, p);
    const V3 h = {out[6], out[7], out[8]};
    const V3 t = constVec(T.t);
    const Ref m = p[9];
    const Ref th = dot(t, h), tt = g_.constant(T.t.squaredNorm());
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) {
        Ref e = out[tensorIndex(i, j)];
        if (i == j) e = g_.add(e, g_.add(g_.mul(g_.constant(2.0), th), g_.mul(m, tt)));
        e = g_.sub(e, g_.add(g_.mul(h[i], t[j]), g_.mul(t[i], h[j])));
        e = g_.sub(e, g_.mul(m, g_.mul(t[i], t[j])));
        out[tensorIndex(i, j)] = e;
      }
    for (int i = 0; i < 3; ++i) out[6 + i] = g_.add(h[i], g_.mul(m, t[i]));
    out[9] = m;
    return out;
  }

  // The body carried through the joint rotation J (x_before = J x_after): J I J^T and J h.
  // About a coordinate axis a only the plane of the other two axes b, d turns. `form` says how
  // the plane block of the tensor is written:
  //   1  entry by entry, I'_bb = cc I_bb + ss I_dd - 2 cs I_bd, I'_dd likewise;
  //   2  I'_dd = I_bb + I_dd - I'_bb (trace kept; cheaper when both are needed);
  //   3  as m (e_bb + e_dd) + h (e_bb - e_dd) + I'_bd (e_bd + e_db), m = (I_bb + I_dd) / 2
  //      unchanged by the rotation and (h, I'_bd) the pair ((I_bb - I_dd) / 2, I_bd) turned
  //      by 2q: the moment of m is m (dw_b - w_d w_a, dw_d + w_b w_a, 0), sums that equal the
  //      parent's in this frame.
  Body rotateParams(const Eigen::Vector3d& axis, Ref c, Ref s, const P10& p, int form) {
    int a = -1;
    for (int i = 0; i < 3; ++i)
      if (std::abs(axis[i]) == 1.0) a = i;
    if (a < 0) {  // general axis
      return body(turned(rodrigues(axis, c, s), p));
    }
    // (b, d, a) right-handed; about -e_a the angle changes sign.
    const int b = (a + 1) % 3, d = (a + 2) % 3;
    if (axis[a] < 0) s = -s;
    const Ref bb = p[tensorIndex(b, b)], dd = p[tensorIndex(d, d)], bd = p[tensorIndex(b, d)];
    const Ref ba = p[tensorIndex(b, a)], da = p[tensorIndex(d, a)];
    Body out;
    auto put = [&out](Ref par, std::initializer_list<std::array<int, 3>> entries) {
      Sym3 T{};
      for (const auto& e : entries) T[e[0]][e[1]] = T[e[1]][e[0]] = e[2];
      out.inertia.emplace_back(par, T);
    };
    if (form == 3) {
      // only the double angle: with 2 s, sin 2q = c (2 s), cos 2q = 1 - s (2 s)
      const Ref s2 = g_.mul(g_.constant(2.0), s);
      const Ref cos2 = g_.sub(Graph::one(), g_.mul(s, s2)), sin2 = g_.mul(c, s2);
      const Ref half = g_.constant(0.5);
      const Ref m = g_.mul(half, g_.add(bb, dd)), dh = g_.mul(half, g_.sub(bb, dd));
      put(m, {{b, b, 1}, {d, d, 1}});
      put(g_.sub(g_.mul(cos2, dh), g_.mul(sin2, bd)), {{b, b, 1}, {d, d, -1}});
      put(g_.add(g_.mul(sin2, dh), g_.mul(cos2, bd)), {{b, d, 1}});
    } else {
      const Ref cc = g_.mul(c, c), ss = g_.mul(s, s), cs = g_.mul(c, s);
      const Ref cos2 = g_.sub(cc, ss), sin2 = g_.mul(g_.constant(2.0), cs);
      const Ref bd2 = g_.mul(sin2, bd);
      const Ref nbb = g_.sub(g_.add(g_.mul(cc, bb), g_.mul(ss, dd)), bd2);
      put(nbb, {{b, b, 1}});
      put(form == 2 ? g_.sub(g_.add(bb, dd), nbb)
                    : g_.add(g_.add(g_.mul(ss, bb), g_.mul(cc, dd)), bd2),
          {{d, d, 1}});
      put(g_.add(g_.mul(cs, g_.sub(bb, dd)), g_.mul(cos2, bd)), {{b, d, 1}});
    }
    put(p[tensorIndex(a, a)], {{a, a, 1}});
    put(g_.sub(g_.mul(c, ba), g_.mul(s, da)), {{b, a, 1}});
    put(g_.add(g_.mul(s, ba), g_.mul(c, da)), {{d, a, 1}});
    const Ref hb = p[6 + b], hd = p[6 + d];
    out.ms[b] = g_.sub(g_.mul(c, hb), g_.mul(s, hd));
    out.ms[d] = g_.add(g_.mul(s, hb), g_.mul(c, hd));
    out.ms[a] = p[6 + a];
    out.mass = p[9];
    return out;
  }

  Motion rigidForward(const Rigid& T, const Motion& m) {
    if (T.identity()) return m;
    const M3 R = constMat(T.R);
    Motion o;
    V3 a = m.a;
    if (!T.t.isZero(0.0)) a = addv(a, uTimes(m, constVec(T.t)));
    o.w = mulT(R, m.w);
    o.dw = mulT(R, m.dw);
    o.a = mulT(R, a);
    return o;
  }
  Pending rigidBackward(const Rigid& T, Pending w) {
    if (T.identity()) return w;
    const M3 R = constMat(T.R);
    Pending o;
    o.f = rotate(R, w.f);
    o.n = rotate(R, w.n);
    if (!T.t.isZero(0.0)) {
      const V3 m = cross(constVec(T.t), values(o.f));
      for (int i = 0; i < 3; ++i) o.n[i].rest = g_.add(o.n[i].rest, m[i]);
    }
    return o;
  }

  // The node of a pending component (written once, then kept as that node).
  Ref value(Component& c) {
    if (!c.terms.empty()) {
      c.rest = g_.add(c.rest, linearForm(c.terms));
      c.terms.clear();
    }
    return c.rest;
  }
  V3 values(std::array<Component, 3>& v) { return {value(v[0]), value(v[1]), value(v[2])}; }

  // u . v, writing only the components u needs.
  Ref along(const V3& u, std::array<Component, 3>& v) {
    Ref t = Graph::zero();
    for (int i = 0; i < 3; ++i)
      if (u[i] != Graph::zero()) t = g_.add(t, g_.mul(u[i], value(v[i])));
    return t;
  }

  static Component negated(Component c) {
    for (auto& t : c.terms) t.first = -t.first;
    c.rest = -c.rest;
    return c;
  }

  // R x; a row of R that is a signed unit vector carries that component as it is.
  std::array<Component, 3> rotate(const M3& R, std::array<Component, 3>& x) {
    int carried[3];
    std::array<bool, 3> needed{};
    for (int i = 0; i < 3; ++i) {
      carried[i] = -1;
      int nonzero = 0, j0 = -1;
      for (int j = 0; j < 3; ++j)
        if (R[i][j] != Graph::zero()) {
          ++nonzero;
          j0 = j;
        }
      if (nonzero == 1 && R[i][j0].abs() == Graph::one()) carried[i] = j0;
      if (carried[i] < 0)
        for (int j = 0; j < 3; ++j)
          if (R[i][j] != Graph::zero()) needed[j] = true;
    }
    for (int j = 0; j < 3; ++j)
      if (needed[j]) value(x[j]);
    std::array<Component, 3> y;
    for (int i = 0; i < 3; ++i) {
      if (carried[i] >= 0) {
        y[i] = R[i][carried[i]].negative() ? negated(x[carried[i]]) : x[carried[i]];
      } else {
        y[i].rest = dot(R[i], {x[0].rest, x[1].rest, x[2].rest});
      }
    }
    return y;
  }

  void append(Pending& w, Pending own) {
    for (int i = 0; i < 3; ++i) {
      w.n[i].terms.insert(w.n[i].terms.end(), own.n[i].terms.begin(), own.n[i].terms.end());
      w.f[i].terms.insert(w.f[i].terms.end(), own.f[i].terms.begin(), own.f[i].terms.end());
      w.n[i].rest = g_.add(w.n[i].rest, own.n[i].rest);
      w.f[i].rest = g_.add(w.f[i].rest, own.f[i].rest);
    }
  }

  // sum_k coef_k * param_k with equal coefficients (up to sign) gathered first.
  Ref linearForm(const std::vector<std::pair<Ref, Ref>>& terms) {
    std::vector<std::pair<Ref, Ref>> groups;
    for (const auto& [c, p] : terms) {
      if (c == Graph::zero() || p == Graph::zero()) continue;
      const Ref ca = c.abs(), ps = p.negatedIf(c.negative());
      bool found = false;
      for (auto& gr : groups)
        if (gr.first == ca) {
          gr.second = g_.add(gr.second, ps);
          found = true;
          break;
        }
      if (!found) groups.emplace_back(ca, ps);
    }
    Ref s = Graph::zero();
    for (const auto& [c, p] : groups) s = g_.add(s, g_.mul(c, p));
    return s;
  }

  // A kinematic coefficient of the wrench: an integer combination of the angular
  // acceleration components dw_k and the products w_i w_j.
  struct Lin {
    std::array<int, 3> dw{};
    std::array<std::array<int, 3>, 3> ww{};  // upper triangle used
    void addProduct(int i, int j, int c) { ww[std::min(i, j)][std::max(i, j)] += c; }
  };

  // coefficient of a parameter whose tensor is T in the moment n = I dw + w x (I w):
  // T dw + w x (T w)
  std::array<Lin, 3> inertiaCoefficients(const Sym3& T) {
    std::array<Lin, 3> out;
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < 3; ++k) out[i].dw[k] = T[i][k];
      const int j1 = (i + 1) % 3, j2 = (i + 2) % 3;
      for (int l = 0; l < 3; ++l) {
        // (w x T w)_i = w_j1 (T w)_j2 - w_j2 (T w)_j1
        if (T[j2][l]) out[i].addProduct(j1, l, T[j2][l]);
        if (T[j1][l]) out[i].addProduct(j2, l, -T[j1][l]);
      }
    }
    return out;
  }

  Ref scaled(Ref x, int c) {
    if (c == 1) return x;
    if (c == -1) return -x;
    return g_.mul(g_.constant(c), x);
  }

  // The node of a coefficient: dw_k +- w_i w_j through dwPlusWW (shared sums), anything else
  // term by term.
  Ref materialise(const Motion& m, const Lin& c) {
    std::vector<std::pair<int, int>> dws;  // (k, coefficient)
    std::vector<std::array<int, 3>> wws;   // (i, j, coefficient)
    for (int k = 0; k < 3; ++k)
      if (c.dw[k]) dws.push_back({k, c.dw[k]});
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j)
        if (c.ww[i][j]) wws.push_back({i, j, c.ww[i][j]});
    if (dws.size() == 1 && wws.size() == 1 && std::abs(dws[0].second) == 1 &&
        std::abs(wws[0][2]) == 1) {
      const bool negate = dws[0].second < 0;
      const bool plus = (wws[0][2] > 0) != negate;
      return dwPlusWW(m, dws[0].first, wws[0][0], wws[0][1], plus).negatedIf(negate);
    }
    Ref r = Graph::zero();
    for (const auto& [k, cf] : dws) r = g_.add(r, scaled(m.dw[k], cf));
    for (const auto& t : wws) r = g_.add(r, scaled(g_.mul(m.w[t[0]], m.w[t[1]]), t[2]));
    return r;
  }

  // Wrench of one body about the frame origin, in the frame, linear in its parameters.
  Pending linkWrench(const Motion& m, const Body& body, bool moment_of_ms = true) {
    Pending w;
    // Inertia: n += I dw + w x (I w), I = sum of parameter * basis tensor.
    for (const auto& [par, T] : body.inertia) {
      if (par == Graph::zero()) continue;
      const auto coef = inertiaCoefficients(T);
      for (int i = 0; i < 3; ++i) w.n[i].terms.emplace_back(materialise(m, coef[i]), par);
    }
    // First moments: n += MS x a, f += U MS.
    for (int j = 0; j < 3; ++j) {
      const Ref par = body.ms[j];
      if (par == Graph::zero()) continue;
      V3 e = zero_;
      e[j] = Graph::one();
      const V3 cn = cross(e, m.a);
      for (int i = 0; i < 3; ++i) {
        if (moment_of_ms) w.n[i].terms.emplace_back(cn[i], par);
        w.f[i].terms.emplace_back(uEntry(m, i, j), par);
      }
    }
    if (body.mass != Graph::zero())
      for (int i = 0; i < 3; ++i) w.f[i].terms.emplace_back(m.a[i], body.mass);
    return w;
  }

  // The ten classical parameters as a body: each inertia entry with its unit tensor.
  static Body body(const P10& p) {
    Body b;
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) {
        Sym3 T{};
        T[i][j] = T[j][i] = 1;
        b.inertia.emplace_back(p[tensorIndex(i, j)], T);
      }
    b.ms = {p[6], p[7], p[8]};
    b.mass = p[9];
    return b;
  }

  Graph& g_;
  const Model& model_;
  std::vector<JointStages> stages_;
  Eigen::Vector3d gravity_;
  V3 zero_;
  std::vector<int> iq_, iv_;  // each joint's first configuration and velocity coordinate
  std::vector<int> contacts_;
  bool contactWorld_ = true;
  std::vector<M3> quat_;   // S of each free-flyer's rotation R = 1 + 2 S
  std::vector<M3> rootR_;  // the rotation of each root joint's motion
  std::vector<Ref> q_, dq_, ddq_;
  std::vector<M3> jointR_;
  std::vector<Ref> jointC_, jointS_;
  std::vector<Motion> link_, linkPre_;
  std::vector<V3> afterA_;  // acceleration of the joint origin in the axes after the motion
};

}  // namespace mindyn::codegen::internal
