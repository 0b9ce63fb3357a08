#include "mindyn/kinematics.hpp"

#include <kdl/rigidbodyinertia.hpp>
#include <kdl/rotationalinertia.hpp>
#include <kdl/segment.hpp>
#include <stdexcept>
#include <string>

namespace mindyn {
namespace {

KDL::Vector toKdl(const Eigen::Vector3d& v) { return KDL::Vector(v.x(), v.y(), v.z()); }

/// KDL inertia (mass, COM, inertia about the COM) of ten classical parameters about the origin.
KDL::RigidBodyInertia toKdlInertia(const Eigen::Ref<const Eigen::VectorXd>& p,
                                   const std::string& link) {
  const double m = p[9];
  const Eigen::Vector3d h = p.segment<3>(6);
  const Eigen::Matrix3d Io = inertiaTensor(p);
  if (m < 0.0) throw ModelError("link '" + link + "' has negative mass " + std::to_string(m));
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  Eigen::Matrix3d Ic = Io;
  if (m > 0.0) {
    c = h / m;
    Ic = Io - m * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
  } else if (h.norm() > 0.0) {
    throw ModelError("link '" + link +
                     "' has zero mass but nonzero first moments, which KDL cannot represent");
  }
  return KDL::RigidBodyInertia(
      m, toKdl(c),
      KDL::RotationalInertia(Ic(0, 0), Ic(1, 1), Ic(2, 2), Ic(0, 1), Ic(0, 2), Ic(1, 2)));
}

}  // namespace

Eigen::Isometry3d toEigen(const KDL::Frame& frame) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) T.linear()(r, c) = frame.M(r, c);
    T.translation()[r] = frame.p[r];
  }
  return T;
}

KDL::Frame toKdl(const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d& R = T.linear();
  return KDL::Frame(KDL::Rotation(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0),
                                  R(2, 1), R(2, 2)),
                    toKdl(Eigen::Vector3d(T.translation())));
}

KDL::Chain toKdlChain(const Model& model, bool with_inertia) {
  requireSingleDof(model, "the KDL kinematics");
  model.validate();
  if (!model.isSerial())
    throw ModelError("model '" + model.name +
                     "' is a tree; a KDL chain needs a serial chain (load the URDF with a tip "
                     "link to take one chain of it)");
  KDL::Chain chain;
  for (int k = 0; k < model.nq(); ++k) {
    const Joint& j = model.joints[k];
    const std::string& link = model.link_names[k + 1];
    // KDL's joint turns about (or slides along) an axis through `origin`, both in the segment's
    // base frame; the segment's tip is then the joint motion applied to f_tip = pre * post.
    const KDL::Joint joint(
        j.name, toKdl(Eigen::Vector3d(j.pre.translation())),
        toKdl(Eigen::Vector3d(j.pre.linear() * j.axis)),
        j.type == JointType::Revolute ? KDL::Joint::RotAxis : KDL::Joint::TransAxis);
    const KDL::RigidBodyInertia inertia =
        with_inertia ? toKdlInertia(model.inertial.segment<10>(10 * k), link)
                     : KDL::RigidBodyInertia::Zero();
    chain.addSegment(KDL::Segment(link, joint, toKdl(j.pre * j.post), inertia));
  }
  if (!model.tool.matrix().isIdentity(0.0))
    chain.addSegment(
        KDL::Segment("tool", KDL::Joint("tool", KDL::Joint::Fixed), toKdl(model.tool)));
  return chain;
}

Kinematics::Kinematics(const Model& model)
    : n_(model.nq()), chain_(std::make_unique<KDL::Chain>(toKdlChain(model, false))) {
  setup();
}

Kinematics::Kinematics(const Kinematics& other)
    : n_(other.n_), chain_(other.chain_ ? std::make_unique<KDL::Chain>(*other.chain_) : nullptr) {
  if (chain_) setup();
}

Kinematics& Kinematics::operator=(const Kinematics& other) {
  if (this != &other) {
    Kinematics copy(other);
    *this = std::move(copy);
  }
  return *this;
}

Kinematics::~Kinematics() = default;

void Kinematics::setup() {
  fk_ = std::make_unique<KDL::ChainFkSolverPos_recursive>(*chain_);
  jac_solver_ = std::make_unique<KDL::ChainJntToJacSolver>(*chain_);
  q_.resize(n_);
  jac_.resize(n_);
}

void Kinematics::setQ(const Eigen::VectorXd& q) {
  if (!chain_) throw std::logic_error("Kinematics object was moved from");
  if (q.size() != n_)
    throw std::invalid_argument("q has " + std::to_string(q.size()) + " entries, expected " +
                                std::to_string(n_));
  q_.data = q;
}

Eigen::Isometry3d Kinematics::pose(const Eigen::VectorXd& q, int link) {
  if (link < -1 || link >= n_)
    throw std::out_of_range("link index " + std::to_string(link) + " is not in -1.." +
                            std::to_string(n_ - 1));
  setQ(q);
  const int rc = fk_->JntToCart(q_, frame_, link < 0 ? -1 : link + 1);
  if (rc < 0) throw std::runtime_error(std::string("KDL forward kinematics: ") + fk_->strError(rc));
  return toEigen(frame_);
}

Eigen::Matrix<double, 6, Eigen::Dynamic> Kinematics::jacobian(const Eigen::VectorXd& q) {
  Eigen::Matrix<double, 6, Eigen::Dynamic> J(6, n_);
  jacobian(q, J);
  return J;
}

void Kinematics::jacobian(const Eigen::VectorXd& q,
                          Eigen::Ref<Eigen::Matrix<double, 6, Eigen::Dynamic>> J) {
  if (J.cols() != n_)
    throw std::invalid_argument("Jacobian output has " + std::to_string(J.cols()) +
                                " columns, expected " + std::to_string(n_));
  setQ(q);
  const int rc = jac_solver_->JntToJac(q_, jac_);
  if (rc < 0) throw std::runtime_error(std::string("KDL Jacobian: ") + jac_solver_->strError(rc));
  J = jac_.data;
}

}  // namespace mindyn
