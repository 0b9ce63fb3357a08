#include "mindyn/transmission.hpp"

#include <Eigen/SVD>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <utility>

#include "mindyn/model.hpp"

namespace mindyn {
namespace {

std::string quoted(const std::vector<std::string>& names) {
  std::string s;
  for (size_t i = 0; i < names.size(); ++i)
    s += (i == 0 ? "'" : i + 1 == names.size() ? " and '" : ", '") + names[i] + "'";
  return s;
}

std::string formatNumber(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

}  // namespace

Eigen::MatrixXd TransmissionGroup::matrix() const {
  const auto a = [&](size_t i) { return actuator_reduction.at(i); };
  const auto j = [&](size_t i) { return i < joint_reduction.size() ? joint_reduction[i] : 1.0; };
  Eigen::MatrixXd M;
  if (type == "SimpleTransmission" || type == kPr2Simple) {
    M.resize(1, 1);
    M << a(0) * j(0);
  } else if (type == "DifferentialTransmission") {
    M.resize(2, 2);
    M << a(0) * j(0), a(0) * j(1), a(1) * j(0), -a(1) * j(1);
  } else if (type == kPr2Wrist) {  // rows right, left; columns flex, roll
    M.resize(2, 2);
    M << a(0) * j(0), -a(0) * j(1), -a(1) * j(0), -a(1) * j(1);
  } else {  // FourBarLinkageTransmission
    M.resize(2, 2);
    M << a(0) * j(0), 0.0, a(1), a(1) * j(1);
  }
  return M;
}

Eigen::VectorXd TransmissionGroup::offsets() const {
  const Eigen::MatrixXd M = matrix();
  Eigen::VectorXd o = Eigen::VectorXd::Zero(M.cols());
  for (size_t k = 0; k < joint_offset.size() && k < static_cast<size_t>(o.size()); ++k)
    o[static_cast<Eigen::Index>(k)] = joint_offset[k];
  return -M * o;
}

int soleJoint(const Eigen::MatrixXd& T, int k) noexcept {
  if (k < 0 || k >= T.rows()) return -1;
  int j = -1;
  for (Eigen::Index a = 0; a < T.cols(); ++a) {
    if (T(k, a) == 0.0) continue;
    if (j >= 0) return -1;  // turns with several joints
    j = static_cast<int>(a);
  }
  if (j < 0) return -1;
  for (Eigen::Index m = 0; m < T.rows(); ++m)
    if (m != k && T(m, j) != 0.0) return -1;  // another motor turns joint j too
  return j;
}

int Transmission::soleJoint(int k) const noexcept { return mindyn::soleJoint(T, k); }

void Transmission::validate(const std::vector<Joint>& joints, const std::string& who) const {
  if (empty()) return;
  const auto n = static_cast<Eigen::Index>(joints.size());
  const Eigen::Index m = nm();
  if (T.rows() != m || T.cols() != n || offset.size() != m || torque_constant.size() != m ||
      static_cast<Eigen::Index>(types.size()) != m)
    throw ModelError(who + ": the transmission matrix is " + std::to_string(T.rows()) + " x " +
                     std::to_string(T.cols()) + " for " + std::to_string(m) + " motors and " +
                     std::to_string(n) + " joints");
  std::set<std::string> seen;
  for (Eigen::Index i = 0; i < m; ++i) {
    const std::string& name = motors[static_cast<size_t>(i)];
    const std::string motor = who + ", motor '" + name + "'";
    if (name.empty()) throw ModelError(who + ": motor " + std::to_string(i + 1) + " has no name");
    if (!seen.insert(name).second)
      throw ModelError(motor + ": two motors have this name; motor names must be unique");
    for (Eigen::Index k = 0; k < n; ++k) {
      const double t = T(i, k);
      if (!std::isfinite(t) || std::abs(t) > kMaxDescriptionValue)
        throw ModelError(motor + ": its coefficient of joint '" +
                         joints[static_cast<size_t>(k)].name + "' is " + formatNumber(t) +
                         ", not a finite number within the bound on a description value");
    }
    if (!std::isfinite(offset[i]) || std::abs(offset[i]) > kMaxDescriptionValue)
      throw ModelError(motor + ": its offset is not a finite number within the bound");
    for (const auto& [v, what] :
         {std::pair<const Eigen::VectorXd*, const char*>{&rotor_inertia, "rotor_inertia"},
          {&viscous, "viscous"},
          {&coulomb, "coulomb"}}) {
      if (v->size() != 0 && v->size() != m)
        throw ModelError(who + ": " + what + " has " + std::to_string(v->size()) + " entries for " +
                         std::to_string(m) + " motors");
      if (v->size() != 0 && !std::isnan((*v)[i]) &&
          (!std::isfinite((*v)[i]) || (*v)[i] < 0 || (*v)[i] > kMaxDescriptionValue))
        throw ModelError(motor + ": its " + what + " is " + formatNumber((*v)[i]) +
                         ", not a finite number >= 0 within the bound on a description value");
    }
    if (third_friction.size() != 0 && third_friction.size() != m)
      throw ModelError(who + ": third_friction has " + std::to_string(third_friction.size()) +
                       " entries for " + std::to_string(m) + " motors");
    if (third_friction.size() != 0 && !std::isnan(third_friction[i]) &&
        !(std::abs(third_friction[i]) <= kMaxDescriptionValue))
      throw ModelError(motor + ": its third friction parameter is " +
                       formatNumber(third_friction[i]) +
                       ", not a finite number within the bound on a description value");
    const double kt = torque_constant[i];
    if (!std::isnan(kt) && (!std::isfinite(kt) || kt == 0.0 || std::abs(kt) > kMaxDescriptionValue))
      throw ModelError(motor + ": its torque constant must be a non-zero finite number");
  }
  // a multi-DOF joint has no motor (a zero column); the single-DOF joints' columns form S
  std::vector<std::string> idle;
  std::vector<Eigen::Index> single;
  for (Eigen::Index k = 0; k < n; ++k) {
    const Joint& j = joints[static_cast<size_t>(k)];
    const bool driven = T.col(k).cwiseAbs().maxCoeff() != 0.0;
    if (j.singleDof()) {
      single.push_back(k);
      if (!driven) idle.push_back(j.name);
    } else if (driven) {
      throw ModelError(who + ", joint '" + j.name + "': a " + toString(j.type) +
                       " joint has several degrees of freedom and no motor of the transmission "
                       "(its column of the transmission matrix must be zero)");
    }
  }
  if (!idle.empty())
    throw ModelError(who + ": no motor drives joint" + (idle.size() > 1 ? "s " : " ") +
                     quoted(idle) +
                     (idle.size() > 1 ? " (their columns of the transmission matrix are zero)"
                                      : " (its column of the transmission matrix is zero)"));
  const auto ns = static_cast<Eigen::Index>(single.size());
  if (ns == 0) return;
  if (m < ns)
    throw ModelError(who + ": " + std::to_string(m) + " motors cannot drive " + std::to_string(ns) +
                     " joints (the transmission matrix needs full column " + "rank)");
  // The rank in the joints' and motors' own units: each column (a joint's unit) and then each
  // non-zero row (a motor's) scaled to norm 1, so that reductions of very different sizes (a
  // block-diagonal T of invertible blocks) are no deficiency, while rows that are multiples of
  // each other stay one.
  Eigen::MatrixXd S(m, ns);
  for (Eigen::Index c = 0; c < ns; ++c) {
    S.col(c) = T.col(single[static_cast<size_t>(c)]);
    S.col(c) /= S.col(c).norm();
  }
  for (Eigen::Index r = 0; r < m; ++r)
    if (const double size = S.row(r).norm(); size > 0.0) S.row(r) /= size;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(S);
  const Eigen::VectorXd s = svd.singularValues();
  const double tol =
      static_cast<double>(std::max(m, ns)) * std::numeric_limits<double>::epsilon() * s[0] * 16.0;
  if (s[ns - 1] <= tol)
    throw ModelError(who + ": the transmission matrix is rank deficient (smallest singular value " +
                     formatNumber(s[ns - 1]) + " of largest " + formatNumber(s[0]) +
                     ", its columns and rows scaled to norm 1): the motors do not determine "
                     "every joint");
}

Transmission assembleTransmission(const std::vector<TransmissionGroup>& groups,
                                  const std::string& format, const std::vector<Joint>& joints,
                                  const std::vector<std::string>& locked_names,
                                  const std::vector<double>& locked_q, const std::string& source,
                                  std::string* notes) {
  Transmission tr;
  if (groups.empty()) return tr;
  const auto fail = [&](const TransmissionGroup& g, const std::string& what) {
    throw ModelError(source + (g.line > 0 ? ":" + std::to_string(g.line) : "") +
                     ": transmission '" + g.name + "': " + what);
  };
  std::map<std::string, int> index;
  for (size_t k = 0; k < joints.size(); ++k) index[joints[k].name] = static_cast<int>(k);
  std::map<std::string, double> locked;
  for (size_t k = 0; k < locked_names.size(); ++k) locked[locked_names[k]] = locked_q.at(k);
  std::map<std::string, std::string> driven_by;  // joint -> transmission
  std::vector<std::string> dropped, held, foreign;
  const auto n = static_cast<Eigen::Index>(joints.size());
  std::vector<Eigen::RowVectorXd> rows;
  std::vector<double> offsets;
  for (const TransmissionGroup& g : groups) {
    const Eigen::MatrixXd M = g.matrix();
    const Eigen::VectorXd c0 = g.offsets();
    bool any = false;
    size_t unknown = 0;
    for (const std::string& j : g.joints) unknown += index.count(j) || locked.count(j) ? 0 : 1;
    if (unknown == g.joints.size()) {  // a transmission of another robot's joints
      foreign.push_back("'" + g.name + "'");
      continue;
    }
    for (const std::string& j : g.joints) {
      if (index.count(j)) {
        const Joint& joint = joints[static_cast<size_t>(index.at(j))];
        if (!joint.singleDof())
          fail(g, "joint '" + j + "' is a " + toString(joint.type) +
                      " joint of several degrees of freedom, which no transmission drives");
        any = true;
      } else if (!locked.count(j)) {
        fail(g, "joint '" + j + "' is not a joint of the robot");
      }
      const auto [it, fresh] = driven_by.emplace(j, g.name);
      if (!fresh)
        fail(g, "joint '" + j + "' is driven by transmission '" + it->second +
                    "' too; a joint belongs to one transmission");
    }
    if (!any) {
      dropped.push_back(g.name);
      continue;
    }
    for (Eigen::Index r = 0; r < M.rows(); ++r) {
      Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(n);
      double c = c0[r];
      for (size_t k = 0; k < g.joints.size(); ++k) {
        const auto it = index.find(g.joints[k]);
        if (it != index.end())
          row[it->second] += M(r, static_cast<Eigen::Index>(k));
        else
          c += M(r, static_cast<Eigen::Index>(k)) * locked.at(g.joints[k]);
      }
      rows.push_back(row);
      offsets.push_back(c);
      tr.motors.push_back(g.actuators.at(static_cast<size_t>(r)));
      tr.types.push_back(g.type);
    }
    for (const std::string& j : g.joints)
      if (!index.count(j)) held.push_back("'" + j + "' (transmission '" + g.name + "')");
    tr.groups.push_back(g);
  }
  std::vector<std::string> direct, passive;
  if (!tr.groups.empty())
    for (size_t k = 0; k < joints.size(); ++k) {
      const std::string& name = joints[k].name;
      if (driven_by.count(name)) continue;
      if (!joints[k].singleDof()) {  // no motor: its column of T stays zero
        passive.push_back("'" + name + "'");
        continue;
      }
      Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(n);
      row[static_cast<Eigen::Index>(k)] = 1.0;
      rows.push_back(row);
      offsets.push_back(0.0);
      tr.motors.push_back(name);
      tr.types.push_back("direct");
      direct.push_back("'" + name + "'");
    }
  const auto m = static_cast<Eigen::Index>(rows.size());
  tr.T.resize(m, n);
  for (Eigen::Index i = 0; i < m; ++i) tr.T.row(i) = rows[static_cast<size_t>(i)];
  tr.offset = Eigen::Map<const Eigen::VectorXd>(offsets.data(), m);
  tr.torque_constant = Eigen::VectorXd::Constant(m, std::numeric_limits<double>::quiet_NaN());
  if (m > 0) tr.format = format;
  std::string text;
  const auto join = [](const std::vector<std::string>& v) {
    std::string s;
    for (const std::string& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
  };
  if (!dropped.empty())
    text += "transmissions of joints that are not moving joints of the model, left out: " +
            join(dropped);
  if (!held.empty())
    text += std::string(text.empty() ? "" : "; ") +
            "joints locked in the model add a constant to their motors' positions: " + join(held);
  if (!foreign.empty())
    text += std::string(text.empty() ? "" : "; ") +
            "transmissions naming no joint of the description, left out: " + join(foreign);
  if (!direct.empty())
    text += std::string(text.empty() ? "" : "; ") +
            "joints without a transmission, driven directly (a motor of their name, ratio 1): " +
            join(direct);
  if (!passive.empty())
    text += std::string(text.empty() ? "" : "; ") +
            "joints of several degrees of freedom, driven by no motor (a zero column of the "
            "transmission matrix): " +
            join(passive);
  if (notes && !text.empty()) *notes += (notes->empty() ? "" : "; ") + text;
  return tr;
}

}  // namespace mindyn
