#include "mindyn/model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "mindyn/data.hpp"

namespace mindyn {

namespace {
const char* const kJointNames[] = {"revolute",    "prismatic", "spherical", "universal",
                                   "cylindrical", "planar",    "floating"};
constexpr int kJointNq[] = {1, 1, 4, 2, 2, 4, 7};
constexpr int kJointNv[] = {1, 1, 3, 2, 2, 3, 6};

/// `v` in 6 significant digits: a small or large value keeps its size (std::to_string writes
/// -1e-07 as -0.000000).
std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}
}  // namespace

const char* toString(JointType type) { return kJointNames[static_cast<int>(type)]; }
int configSize(JointType type) { return kJointNq[static_cast<int>(type)]; }
int velocitySize(JointType type) { return kJointNv[static_cast<int>(type)]; }

Eigen::Isometry3d Joint::transform(double q) const {
  Eigen::Isometry3d J = Eigen::Isometry3d::Identity();
  if (type == JointType::Revolute)
    J.linear() = Eigen::AngleAxisd(q, axis).toRotationMatrix();
  else
    J.translation() = axis * q;
  return pre * J * post;
}

Eigen::Isometry3d Joint::transform(const double* q) const {
  Eigen::Isometry3d J = Eigen::Isometry3d::Identity();
  switch (type) {
    case JointType::Revolute:
    case JointType::Prismatic:
      return transform(q[0]);
    case JointType::Spherical:
      J.linear() = Eigen::Quaterniond(q[3], q[0], q[1], q[2]).toRotationMatrix();
      break;
    case JointType::Universal:
      J.linear() =
          (Eigen::AngleAxisd(q[0], axis) * Eigen::AngleAxisd(q[1], axis2)).toRotationMatrix();
      break;
    case JointType::Cylindrical:
      J.linear() = Eigen::AngleAxisd(q[1], axis).toRotationMatrix();
      J.translation() = axis * q[0];
      break;
    case JointType::Planar:
      J.linear() << q[2], -q[3], 0.0, q[3], q[2], 0.0, 0.0, 0.0, 1.0;
      J.translation() << q[0], q[1], 0.0;
      break;
    case JointType::FreeFlyer:
      J.linear() = Eigen::Quaterniond(q[6], q[3], q[4], q[5]).toRotationMatrix();
      J.translation() << q[0], q[1], q[2];
      break;
  }
  return pre * J * post;
}

int Model::configSize() const {
  int s = 0;
  for (const Joint& j : joints) s += j.nq();
  return s;
}

int Model::velocitySize() const {
  int s = 0;
  for (const Joint& j : joints) s += j.nv();
  return s;
}

bool Model::singleDof() const {
  for (const Joint& j : joints)
    if (!j.singleDof()) return false;
  return true;
}

void requireSingleDof(const Model& model, const std::string& what) {
  for (const Joint& j : model.joints)
    if (!j.singleDof())
      throw ModelError(what + " takes revolute and prismatic joints only; model '" + model.name +
                       "' has the " + toString(j.type) + " joint '" + j.name +
                       "' (its inverse dynamics, regressor, mass matrix, forward dynamics, "
                       "energies, momentum, Slotine-Li regressor, Coriolis matrix and base "
                       "parameters are available)");
}

SingleDofExpansion expandToSingleDof(const Model& model, bool keep_free_flyer_roots) {
  model.validate();  // sizes (inertial, link names, parents) are used below
  SingleDofExpansion out;
  const int n = model.nq();
  if (model.singleDof()) {
    out.model = model;
    for (int k = 0; k < n; ++k) out.link.push_back(k);
    for (int c = 0; c < 10 * n; ++c) out.column.push_back(c);
    return out;
  }
  Model& m = out.model;
  m.name = model.name;
  m.source = model.source;
  m.convention = model.convention;
  m.gravity = model.gravity;
  m.tool = model.tool;
  m.synthetic_inertia = model.synthetic_inertia;
  m.link_names.push_back(model.link_names.empty() ? "base" : model.link_names[0]);
  std::vector<int> last(static_cast<std::size_t>(n));  // each joint's last factor
  std::vector<std::pair<JointType, Eigen::Vector3d>> factors;
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(),
                        z = Eigen::Vector3d::UnitZ();
  constexpr JointType R = JointType::Revolute, P = JointType::Prismatic;
  for (int k = 0; k < n; ++k) {
    const Joint& j = model.joints[static_cast<std::size_t>(k)];
    switch (j.type) {
      case JointType::Revolute:
      case JointType::Prismatic:
        factors = {{j.type, j.axis}};
        break;
      case JointType::Spherical:
        factors = {{R, z}, {R, y}, {R, x}};
        break;
      case JointType::Universal:
        factors = {{R, j.axis}, {R, j.axis2}};
        break;
      case JointType::Cylindrical:
        factors = {{P, j.axis}, {R, j.axis}};
        break;
      case JointType::Planar:
        factors = {{P, x}, {P, y}, {R, z}};
        break;
      case JointType::FreeFlyer:
        if (keep_free_flyer_roots && model.parent(k) < 0)
          factors = {{JointType::FreeFlyer, j.axis}};
        else
          factors = {{P, x}, {P, y}, {P, z}, {R, z}, {R, y}, {R, x}};
        break;
    }
    const int f = static_cast<int>(factors.size());
    const int p = model.parent(k);
    for (int i = 0; i < f; ++i) {
      Joint e;
      e.name = f == 1 ? j.name : j.name + "[" + std::to_string(i + 1) + "]";
      e.type = factors[static_cast<std::size_t>(i)].first;
      e.axis = factors[static_cast<std::size_t>(i)].second;
      if (i == 0) e.pre = j.pre;
      if (i == f - 1) {
        e.post = j.post;
        if (f == 1) e.limits = j.limits;
      }
      m.parents.push_back(i > 0 ? m.nq() - 1 : (p < 0 ? -1 : last[static_cast<std::size_t>(p)]));
      m.joints.push_back(e);
      out.link.push_back(i == f - 1 ? k : -1);
      m.link_names.push_back(i == f - 1 ? model.link_names[static_cast<std::size_t>(k + 1)]
                                        : e.name + ".link");
    }
    last[static_cast<std::size_t>(k)] = m.nq() - 1;
  }
  const int ne = m.nq();
  m.inertial = Eigen::VectorXd::Zero(10 * ne);
  for (int e = 0; e < ne; ++e) {
    const int k = out.link[static_cast<std::size_t>(e)];
    if (k >= 0) m.inertial.segment<10>(10 * e) = model.inertial.segment<10>(10 * k);
  }
  out.column.resize(static_cast<std::size_t>(10 * n));
  for (int e = 0; e < ne; ++e)
    if (const int k = out.link[static_cast<std::size_t>(e)]; k >= 0)
      for (int c = 0; c < 10; ++c) out.column[static_cast<std::size_t>(10 * k + c)] = 10 * e + c;
  m.rotor_inertia = m.viscous = m.coulomb = Eigen::VectorXd::Zero(ne);
  return out;
}

void checkConfiguration(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q) {
  if (q.size() != model.configSize())
    throw std::invalid_argument("q has " + std::to_string(q.size()) +
                                " entries; the model's "
                                "configuration has " +
                                std::to_string(model.configSize()));
  int i = 0;
  for (const Joint& j : model.joints) {
    int start = -1, len = 0;
    if (j.type == JointType::Spherical) start = 0, len = 4;
    if (j.type == JointType::FreeFlyer) start = 3, len = 4;
    if (j.type == JointType::Planar) start = 2, len = 2;
    if (start >= 0) {
      const double norm = q.segment(i + start, len).norm();
      if (!(std::abs(norm - 1.0) <= 1e-6))
        throw std::invalid_argument(
            std::string("the ") + (len == 4 ? "quaternion" : "(cos, sin) pair") + " of the " +
            toString(j.type) + " joint '" + j.name + "' (q entries " + std::to_string(i + start) +
            " to " + std::to_string(i + start + len - 1) + ") has norm " + std::to_string(norm) +
            ", not 1");
    }
    i += j.nq();
  }
}

bool Model::isSerial() const {
  for (int k = 0; k < nq(); ++k)
    if (parent(k) != k - 1) return false;
  return true;
}

bool Model::supports(int j, int k) const {
  while (k > j) k = parent(k);
  return k == j;
}

std::string offsetName(int k) { return kOffsetPrefix + std::to_string(k + 1); }

ParameterLayout ParameterLayout::fromSize(int n, long size, int friction_columns) {
  for (int r = 0; r < 2; ++r)
    for (int f = 0; f < 2; ++f) {
      ParameterLayout l{r == 1, f == 1};
      l.friction_columns = friction_columns;
      if (l.size(n) == size) return l;
    }
  const std::string fr = friction_columns == 3 ? "Fv, Fc, F3" : "Fv, Fc";
  throw ModelError("a parameter vector of " + std::to_string(size) +
                   " entries fits no layout for " + std::to_string(n) + " joints (expected " +
                   std::to_string(10 * n) + ", " + std::to_string(11 * n) + " with Ia, " +
                   std::to_string((10 + friction_columns) * n) + " with " + fr + ", or " +
                   std::to_string((11 + friction_columns) * n) + " with all)");
}

namespace {
const char* const kFrictionNames[] = {"coulomb", "asymmetric", "smooth", "stribeck"};
}  // namespace

const char* toString(FrictionKind kind) { return kFrictionNames[static_cast<int>(kind)]; }

FrictionKind frictionKindOf(const std::string& name) {
  for (int k = 0; k < 4; ++k)
    if (name == kFrictionNames[k]) return static_cast<FrictionKind>(k);
  throw ModelError("friction model must be coulomb, asymmetric, smooth or stribeck, not '" +
                   escapeControl(name) + "'");
}

void FrictionModel::validate(int n) const {
  const std::string kind_name = toString(kind);
  if (!scaled()) {
    if (velocity.size() != 0)
      throw ModelError("the " + kind_name + " friction model takes no velocity");
    return;
  }
  if (velocity.size() != n)
    throw ModelError("the " + kind_name + " friction model needs a velocity per joint (" +
                     std::to_string(n) + "), got " + std::to_string(velocity.size()));
  for (int k = 0; k < n; ++k)
    if (!std::isfinite(velocity[k]) || !(velocity[k] > 0.0) || velocity[k] > kMaxDescriptionValue)
      throw ModelError("the " + kind_name + " friction model's velocity " + std::to_string(k + 1) +
                       " must be positive, finite and at most 1e16, not " + number(velocity[k]));
}

std::vector<std::string> Model::parameterNames(ParameterLayout layout) const {
  const char* third = friction_model.kind == FrictionKind::Stribeck ? "Fs" : "Fa";
  std::vector<std::string> names;
  names.reserve(layout.size(nq()));
  for (int k = 0; k < nq(); ++k) {
    const std::string idx = std::to_string(k + 1);
    for (const char* s : kInertialNames) names.push_back(s + idx);
    if (layout.rotor) names.push_back("Ia" + idx);
    if (layout.friction) {
      names.push_back("Fv" + idx);
      names.push_back("Fc" + idx);
      if (layout.friction_columns == 3) names.push_back(third + idx);
    }
  }
  if (layout.offset)
    for (int k = 0; k < nq(); ++k) names.push_back(offsetName(k));
  return names;
}

Eigen::VectorXd Model::parameters(ParameterLayout layout) const {
  const int n = nq();
  Eigen::VectorXd p = Eigen::VectorXd::Zero(layout.size(n));  // offsets: 0 unless given
  if (layout.offset && torque_offset.size() == n)
    for (int k = 0; k < n; ++k) p[layout.offsetIndex(n, k)] = torque_offset[k];
  for (int k = 0; k < n; ++k) {
    p.segment<10>(k * layout.perLink()) = inertial.segment<10>(10 * k);
    if (layout.rotor) p[layout.rotorIndex(k)] = rotor_inertia[k];
    if (layout.friction) {
      p[layout.viscousIndex(k)] = viscous[k];
      p[layout.coulombIndex(k)] = coulomb[k];
      if (layout.friction_columns == 3)
        p[layout.thirdFrictionIndex(k)] = third_friction.size() == n ? third_friction[k] : 0.0;
    }
  }
  if (!motorSide() || transmission.nm() != n) return p;
  // On the motor side slot k is motor k: its own values when the description gives them
  // (Transmission), otherwise from the joints'. A motor that alone drives one joint alone (row
  // k of T = r e_j, column j = r e_k: Transmission::soleJoint) acts on it as r^2 Ia, r^2 Fv,
  // |r| Fc: its values are the joint's divided so. A motor that turns with several joints (or
  // shares its joint): its own values, 0 where none is given.
  const Eigen::MatrixXd& T = transmission.T;
  for (int k = 0; k < n; ++k) {
    const int j = transmission.soleJoint(k);
    const bool alone = j >= 0;
    const double r = alone ? T(k, j) : 0.0;
    // the motor's own value when the description gives it
    auto own = [k](const Eigen::VectorXd& v, double derived) {
      return v.size() > k && !std::isnan(v[k]) ? v[k] : derived;
    };
    if (layout.rotor)
      p[layout.rotorIndex(k)] =
          own(transmission.rotor_inertia, alone ? rotor_inertia[j] / (r * r) : 0.0);
    if (layout.friction) {
      p[layout.viscousIndex(k)] = own(transmission.viscous, alone ? viscous[j] / (r * r) : 0.0);
      p[layout.coulombIndex(k)] = own(transmission.coulomb, alone ? coulomb[j] / std::abs(r) : 0.0);
      // r Fa |sign(r dq)| = (r Fa) |sign(dq)|; r Fs sign(r dq) ... = |r| Fs sign(dq) ...
      if (layout.friction_columns == 3) {
        const double t = third_friction.size() == n && alone ? third_friction[j] : 0.0;
        p[layout.thirdFrictionIndex(k)] = own(
            transmission.third_friction,
            alone ? t / (friction_model.kind == FrictionKind::Asymmetric ? r : std::abs(r)) : 0.0);
      }
    }
  }
  return p;
}

namespace {

/// Throws unless |value| <= bound; `what` names the value and `where()` the place. `where` is
/// only called on an error, so that checking a valid model builds no message.
template <class Where>
void checkBound(const Where& where, const char* what, double value, double bound) {
  if (std::abs(value) > bound)
    throw ModelError(where() + ": " + what + " " + number(value) + " exceeds the bound " +
                     number(bound) + " on its magnitude");
}

bool isRigid(const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d R = T.linear();
  return T.matrix().allFinite() &&
         (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-9 &&
         R.determinant() > 0.0;
}
}  // namespace

void Model::validate() const {
  const int n = nq();
  const auto who = [this] {
    return (source.empty() || source == "generated" ? std::string() : source + ": ") +
           (name.empty() ? std::string("model") : "model '" + name + "'");
  };
  if (n == 0) throw ModelError(who() + " has no moving joint");
  if (n > kMaxModelJoints)
    throw ModelError(who() + " has " + std::to_string(n) + " joints; at most " +
                     std::to_string(kMaxModelJoints) + " are supported");
  if (inertial.size() != 10 * n)
    throw ModelError(who() + ": " + std::to_string(inertial.size()) + " inertial parameters for " +
                     std::to_string(n) + " links (expected " + std::to_string(10 * n) + ")");
  for (const auto* v : {&rotor_inertia, &viscous, &coulomb})
    if (v->size() != n) throw ModelError(who() + ": per-joint parameter vector of wrong size");
  if (!inertial.allFinite()) throw ModelError(who() + ": inertial parameters are not finite");
  if (third_friction.size() != 0 && third_friction.size() != n)
    throw ModelError(who() + ": " + std::to_string(third_friction.size()) +
                     " third friction parameters for " + std::to_string(n) + " joints");
  if (!rotor_inertia.allFinite() || !viscous.allFinite() || !coulomb.allFinite() ||
      !third_friction.allFinite())
    throw ModelError(who() + ": rotor inertia or friction is not finite");
  if (torque_offset.size() != 0 && torque_offset.size() != n)
    throw ModelError(who() + ": " + std::to_string(torque_offset.size()) + " torque offsets for " +
                     std::to_string(n) + " joints");
  if (!torque_offset.allFinite()) throw ModelError(who() + ": a torque offset is not finite");
  try {
    friction_model.validate(n);
  } catch (const ModelError& e) {
    throw ModelError(who() + ": " + e.what());
  }
  if (!gravity.allFinite()) throw ModelError(who() + ": gravity is not finite");
  if (link_names.size() != static_cast<size_t>(n + 1))
    throw ModelError(who() + ": expected " + std::to_string(n + 1) + " link names");
  if (!parents.empty()) {
    if (parents.size() != static_cast<size_t>(n))
      throw ModelError(who() + ": " + std::to_string(parents.size()) + " parent indices for " +
                       std::to_string(n) + " joints");
    for (int k = 0; k < n; ++k)
      if (parents[k] < -1 || parents[k] >= k)
        throw ModelError(who() + ", joint '" + joints[k].name + "': parent index " +
                         std::to_string(parents[k]) + " is not in [-1, " + std::to_string(k - 1) +
                         "] (a parent joint comes before its children; -1 is the base)");
  }
  transmission.validate(joints, who());
  const double V = kMaxDescriptionValue;
  const double L = 100 * V;  // a length or mass folded from up to 100 inputs
  for (int i = 0; i < 3; ++i) checkBound(who, "gravity component", gravity[i], V);
  for (int k = 0; k < n; ++k) {
    const auto link = [&] { return who() + ", link '" + link_names[k + 1] + "'"; };
    const auto p = inertial.segment<10>(10 * k);
    for (int i = 0; i < 10; ++i) {
      const double bound = i == 9 ? L : i >= 6 ? L * L : L * L * L;
      if (std::abs(p[i]) > bound)  // the name is built only for the error
        checkBound(link, (std::string("inertial parameter ") + kInertialNames[i]).c_str(), p[i],
                   bound);
    }
    const auto joint = [&] { return who() + ", joint '" + joints[k].name + "'"; };
    checkBound(joint, "rotor inertia", rotor_inertia[k], V);
    checkBound(joint, "viscous friction", viscous[k], V);
    checkBound(joint, "Coulomb friction", coulomb[k], V);
    if (third_friction.size() == n)
      checkBound(joint, "third friction parameter", third_friction[k], V);
    if (torque_offset.size() == n) checkBound(joint, "torque offset", torque_offset[k], V);
  }
  for (const Joint& j : joints) {
    const auto joint = [&] { return who() + ", joint '" + j.name + "'"; };
    for (int i = 0; i < 3; ++i) {
      checkBound(joint, "origin translation", j.pre.translation()[i], L);
      checkBound(joint, "origin translation", j.post.translation()[i], L);
    }
    const std::pair<const char*, double> limits[] = {
        {"lower limit", j.limits.lower},         {"upper limit", j.limits.upper},
        {"velocity limit", j.limits.velocity},   {"acceleration limit", j.limits.acceleration},
        {"effort limit", j.limits.effort},       {"drive rated torque", j.drive.rated_torque},
        {"drive gear ratio", j.drive.gear_ratio}};
    for (const auto& [what, value] : limits) {
      if (std::isnan(value)) continue;  // not given
      if (!std::isfinite(value)) throw ModelError(joint() + ": " + what + " is not finite");
      checkBound(joint, what, value, V);
    }
    if (!j.axis.allFinite() || std::abs(j.axis.norm() - 1.0) > 1e-9)
      throw ModelError(joint() + ": axis is not a unit vector");
    if (j.type == JointType::Universal &&
        (!j.axis2.allFinite() || std::abs(j.axis2.norm() - 1.0) > 1e-9 ||
         j.axis.cross(j.axis2).norm() < 1e-6))
      throw ModelError(joint() +
                       ": the universal joint's second axis is not a unit vector "
                       "independent of the first");
    if (!isRigid(j.pre) || !isRigid(j.post))
      throw ModelError(joint() + ": origin is not a rigid transform");
    if (j.limits.lower > j.limits.upper)
      throw ModelError(joint() + ": lower limit above upper limit");
  }
  if (!isRigid(tool)) throw ModelError(who() + ": tool frame is not a rigid transform");
  for (int i = 0; i < 3; ++i) checkBound(who, "tool translation", tool.translation()[i], L);
}

namespace {
/// Length of the valid UTF-8 sequence starting at s[i], or 0 if none starts there.
size_t utf8Length(const unsigned char* s, size_t i, size_t n) {
  const unsigned char c = s[i];
  if (c < 0x80) return 1;
  size_t len = 0;
  unsigned lo = 0x80, hi = 0xBF;  // allowed range of the second byte
  if (c >= 0xC2 && c <= 0xDF) {
    len = 2;
  } else if (c >= 0xE0 && c <= 0xEF) {
    len = 3;
    if (c == 0xE0) lo = 0xA0;  // no overlong forms
    if (c == 0xED) hi = 0x9F;  // no surrogates
  } else if (c >= 0xF0 && c <= 0xF4) {
    len = 4;
    if (c == 0xF0) lo = 0x90;
    if (c == 0xF4) hi = 0x8F;  // nothing above U+10FFFF
  }
  if (len == 0 || i + len > n || s[i + 1] < lo || s[i + 1] > hi) return 0;
  for (size_t k = 2; k < len; ++k)
    if (s[i + k] < 0x80 || s[i + k] > 0xBF) return 0;
  return len;
}
}  // namespace

std::string escapeControl(const std::string& text) {
  const auto* s = reinterpret_cast<const unsigned char*>(text.data());
  const size_t n = text.size();
  std::string out;
  out.reserve(n);
  for (size_t i = 0; i < n;) {
    const unsigned char c = s[i];
    const size_t len = utf8Length(s, i, n);
    if (c == '\n') {
      out += "\\n";
    } else if (c == '\t') {
      out += "\\t";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c < 0x20 || c == 0x7f || len == 0) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    } else {
      out.append(text, i, len);
      i += len;
      continue;
    }
    ++i;
  }
  return out;
}

void requireUtf8(const std::string& text, const std::string& source) {
  const auto* s = reinterpret_cast<const unsigned char*>(text.data());
  const size_t n = text.size();
  for (size_t i = 0; i < n;) {
    const size_t len = utf8Length(s, i, n);
    if (len == 0) {  // report the sequence's first byte, as Python's decoder does
      char buf[64];
      std::snprintf(buf, sizeof buf, " (byte 0x%02x at offset %zu)", s[i], i);
      const long line = 1 + std::count(text.begin(), text.begin() + static_cast<long>(i), '\n');
      throw ModelError(source + ":" + std::to_string(line) + ": not UTF-8 text" + buf);
    }
    i += len;
  }
}

Eigen::Matrix<double, 10, 1> inertialFromCom(double mass, const Eigen::Vector3d& com,
                                             const Eigen::Matrix3d& inertia_com) {
  // Parallel axes: I_o = I_c + m (c^T c 1 - c c^T).
  const Eigen::Matrix3d Io = inertia_com + mass * (com.squaredNorm() * Eigen::Matrix3d::Identity() -
                                                   com * com.transpose());
  Eigen::Matrix<double, 10, 1> p;
  p << Io(0, 0), Io(0, 1), Io(0, 2), Io(1, 1), Io(1, 2), Io(2, 2), mass * com.x(), mass * com.y(),
      mass * com.z(), mass;
  return p;
}

Eigen::Matrix<double, 10, 1> inertialFromUrdf(double mass, const Eigen::Vector3d& com,
                                              const Eigen::Matrix3d& R,
                                              const Eigen::Matrix3d& inertia_com) {
  return inertialFromCom(mass, com, R * inertia_com * R.transpose());
}

Eigen::Matrix3d inertiaTensor(const Eigen::Ref<const Eigen::VectorXd>& p) {
  Eigen::Matrix3d I;
  I << p[0], p[1], p[2], p[1], p[3], p[4], p[2], p[4], p[5];
  return I;
}

Eigen::VectorXd toPinocchioOrder(const Eigen::Ref<const Eigen::VectorXd>& in) {
  if (in.size() % 10 != 0)
    throw ModelError("inertial parameter vector length " + std::to_string(in.size()) +
                     " is not a multiple of 10");
  Eigen::VectorXd out(in.size());
  for (long k = 0; k < in.size() / 10; ++k) {
    const auto a = in.segment<10>(10 * k);
    out.segment<10>(10 * k) << a[9], a[6], a[7], a[8], a[0], a[1], a[3], a[2], a[4], a[5];
  }
  return out;
}

Eigen::VectorXd fromPinocchioOrder(const Eigen::Ref<const Eigen::VectorXd>& in) {
  if (in.size() % 10 != 0)
    throw ModelError("dynamic parameter vector length " + std::to_string(in.size()) +
                     " is not a multiple of 10");
  Eigen::VectorXd out(in.size());
  for (long k = 0; k < in.size() / 10; ++k) {
    const auto b = in.segment<10>(10 * k);
    // b = m, mcx, mcy, mcz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz
    out.segment<10>(10 * k) << b[4], b[5], b[7], b[6], b[8], b[9], b[1], b[2], b[3], b[0];
  }
  return out;
}

Data::Data(const Model& model)
    : n(model.nq()),
      S(n),
      R(n),
      p(n),
      R0(n),
      p0(n),
      v(n),
      a(n),
      f(n),
      zeros(Eigen::VectorXd::Zero(n)),
      unit(Eigen::VectorXd::Zero(n)),
      tmp(Eigen::VectorXd::Zero(n)),
      M(Eigen::MatrixXd::Zero(n, n)),
      llt(n) {
  requireSingleDof(model, "this function");
  for (int k = 0; k < n; ++k) {
    const Joint& j = model.joints[k];
    const Eigen::Matrix3d Rt = j.post.linear().transpose();
    const Eigen::Vector3d pt = -(Rt * j.post.translation());
    Vector6d s;
    if (j.type == JointType::Revolute) {
      s.head<3>() = Rt * j.axis;
      s.tail<3>() = pt.cross(s.head<3>());
    } else {
      s.head<3>().setZero();
      s.tail<3>() = Rt * j.axis;
    }
    S[k] = s;
  }
}

}  // namespace mindyn
