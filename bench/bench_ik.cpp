// Position IK benchmark with TRAC-IK's protocol: random joint vectors inside the limits -> tool
// poses by forward kinematics (KDL) -> solve from the middle of the limits. Success: pose error
// <= 1e-5, the norm of the SE(3) logarithm of T_target^-1 T (metres and radians, as Pinocchio's
// log6 measures it), and every joint inside its limits (revolute angles shifted by multiples of
// 2 pi first: KDL's LMA ignores limits and any solver may return an angle 2 pi away). Time: mean
// wall time per solve, failures included. Final errors: median, 99th percentile and largest over
// all solves, failures included.
//
// Usage: bench_ik [samples] [robot-data-dir]   (default 10000 samples; UR5 and Panda URDFs from
// example-robot-data, PUMA 560 from the bundled YAML)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_lma.hpp>
#include <kdl/chainiksolverpos_nr_jl.hpp>
#include <kdl/chainiksolvervel_pinv.hpp>
#include <random>
#include <string>
#include <vector>

#include "mindyn/description.hpp"
#include "mindyn/ik.hpp"
#include "mindyn/kinematics.hpp"
#include "mindyn/urdf.hpp"

using namespace mindyn;
using Clock = std::chrono::steady_clock;

namespace {

struct Case {
  std::string name;
  Model model;
  double published_success = NAN, published_ms = NAN;  // TRAC-IK, for reference
};

struct Outcome {
  double success = 0, mean_ms = 0, median_ms = 0, max_ms = 0, mean_iterations = 0;
  double err_median = 0, err_p99 = 0, err_max = 0;
};

// Shifts revolute angles by multiples of 2 pi into the limits when possible; true when every
// joint ends inside.
bool wrapIntoLimits(const Model& model, Eigen::VectorXd& q) {
  bool inside = true;
  for (int k = 0; k < model.nq(); ++k) {
    const JointLimits& l = model.joints[k].limits;
    if (!std::isfinite(l.lower) || !std::isfinite(l.upper)) continue;
    if (model.joints[k].type == JointType::Revolute && std::isfinite(q[k])) {
      while (q[k] < l.lower - 1e-12) q[k] += 2 * M_PI;
      while (q[k] > l.upper + 1e-12) q[k] -= 2 * M_PI;
    }
    if (!(q[k] >= l.lower - 1e-12 && q[k] <= l.upper + 1e-12)) inside = false;
  }
  return inside;
}

// |log6(target^-1 T)| for the KDL forward kinematics at q: rotation log from Eigen's angle-axis,
// translation part V(w)^-1 p.
double poseError(KDL::ChainFkSolverPos_recursive& fk, const Eigen::VectorXd& q,
                 const KDL::Frame& target) {
  KDL::JntArray a(q.size());
  a.data = q;
  KDL::Frame f;
  fk.JntToCart(a, f);
  const Eigen::Isometry3d T = toEigen(f), D = toEigen(target);
  const Eigen::Isometry3d M = D.inverse() * T;
  const Eigen::AngleAxisd aa(M.linear());
  const double t = aa.angle();
  const Eigen::Vector3d w = t * aa.axis(), p = M.translation();
  const double k = t < 1e-4 ? 1.0 / 12 + t * t / 720
                            : (1.0 - t * std::sin(t) / (2.0 * (1.0 - std::cos(t)))) / (t * t);
  const Eigen::Vector3d v = p - 0.5 * w.cross(p) + k * w.cross(w.cross(p));
  const double m = std::sqrt(v.squaredNorm() + w.squaredNorm());
  return std::isfinite(m) ? m : INFINITY;
}

double quantile(std::vector<double> x, double f) {
  std::sort(x.begin(), x.end());
  return x[std::min(x.size() - 1, static_cast<size_t>(f * static_cast<double>(x.size())))];
}

template <class Solve>
Outcome run(const Model& model, const std::vector<Eigen::VectorXd>& joints,
            const std::vector<KDL::Frame>& targets, const Eigen::VectorXd& start, Solve&& solve) {
  const KDL::Chain chain = toKdlChain(model, false);
  KDL::ChainFkSolverPos_recursive fk(chain);
  const int n = model.nq();
  std::vector<double> ms(targets.size()), err(targets.size());
  Eigen::VectorXd q(n);
  long ok = 0;
  double iterations = 0;
  for (size_t i = 0; i < targets.size(); ++i) {
    const auto t0 = Clock::now();
    iterations += solve(targets[i], start, q);
    ms[i] = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    Eigen::VectorXd w = q;
    err[i] = poseError(fk, w, targets[i]);
    if (err[i] <= 1e-5 && wrapIntoLimits(model, w)) ++ok;
  }
  (void)joints;
  Outcome o;
  o.success = 100.0 * ok / targets.size();
  double sum = 0;
  for (double x : ms) sum += x;
  o.mean_ms = sum / ms.size();
  std::vector<double> sorted = ms;
  std::sort(sorted.begin(), sorted.end());
  o.median_ms = sorted[sorted.size() / 2];
  o.max_ms = sorted.back();
  o.mean_iterations = iterations / targets.size();
  o.err_median = quantile(err, 0.5);
  o.err_p99 = quantile(err, 0.99);
  o.err_max = quantile(err, 1.0);
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  const int samples = argc > 1 ? std::atoi(argv[1]) : 10000;
  const std::string data = argc > 2 ? argv[2] : MINDYN_ROBOT_DATA_DIR;
  if (samples < 1 || data.empty()) {
    std::fprintf(stderr, "usage: bench_ik [samples] [example-robot-data robots dir]\n");
    return 2;
  }
  std::vector<Case> cases;
  cases.push_back(
      {"UR5", loadUrdf(data + "/ur_description/urdf/ur5_robot.urdf", "tool0"), 99.55, 0.42});
  cases.push_back(
      {"Panda", loadUrdf(data + "/panda_description/urdf/panda.urdf", "panda_link8"), 99.70, 0.38});
  cases.push_back({"PUMA 560", loadYaml(std::string(MINDYN_ROBOT_DIR) + "/puma560.yaml")});

  std::printf(
      "IK benchmark, TRAC-IK protocol: %d random configurations per robot, solved from the\n"
      "middle of the limits; success = |log6(T_target^-1 T)| <= 1e-5 and inside the limits;\n"
      "time = mean per solve including failures; final |log6| over all solves: median, 99th\n"
      "percentile, max. Compiler: %s\n\n",
      samples, MINDYN_BENCH_COMPILER);
  std::printf("%-9s %-26s %9s %9s %9s %9s %7s %10s %9s %9s %9s\n", "robot", "solver", "success%",
              "mean ms", "median", "max ms", "iter", "vs NR_JL", "err med", "err p99", "err max");
  for (const Case& c : cases) {
    const Model& model = c.model;
    const int n = model.nq();
    IkSolver probe(model);
    const Eigen::VectorXd lo = probe.lower(), hi = probe.upper();
    const Eigen::VectorXd mid = 0.5 * (lo + hi);
    std::mt19937 rng(2024);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const KDL::Chain chain = toKdlChain(model, false);
    KDL::ChainFkSolverPos_recursive fk(chain);
    std::vector<Eigen::VectorXd> joints;
    std::vector<KDL::Frame> targets;
    for (int i = 0; i < samples; ++i) {
      Eigen::VectorXd q(n);
      for (int k = 0; k < n; ++k) q[k] = lo[k] + (hi[k] - lo[k]) * u(rng);
      KDL::JntArray a(n);
      a.data = q;
      KDL::Frame f;
      fk.JntToCart(a, f);
      joints.push_back(q);
      targets.push_back(f);
    }

    // mindyn: damped least squares with limits and restarts, 5 ms budget like TRAC-IK's default
    IkSolver solver(model);
    const Outcome ours =
        run(model, joints, targets, mid,
            [&](const KDL::Frame& f, const Eigen::VectorXd& s, Eigen::VectorXd& q) {
              return solver.solve(toEigen(f), s, q).iterations;
            });

    // KDL Newton-Raphson with joint limits (clamping), one attempt of up to 100 iterations
    KDL::JntArray kmin(n), kmax(n);
    kmin.data = lo;
    kmax.data = hi;
    KDL::ChainIkSolverVel_pinv vel(chain);
    KDL::ChainFkSolverPos_recursive fk2(chain);
    KDL::ChainIkSolverPos_NR_JL nrjl(chain, kmin, kmax, fk2, vel, 100, 1e-5);
    KDL::JntArray kin(n), kout(n);
    const Outcome nr = run(model, joints, targets, mid,
                           [&](const KDL::Frame& f, const Eigen::VectorXd& s, Eigen::VectorXd& q) {
                             kin.data = s;
                             nrjl.CartToJnt(kin, f, kout);
                             q = kout.data;
                             return 0;
                           });

    // KDL Levenberg-Marquardt (no limits; answers wrapped into them if possible)
    KDL::ChainIkSolverPos_LMA lma(chain);
    const Outcome lm = run(model, joints, targets, mid,
                           [&](const KDL::Frame& f, const Eigen::VectorXd& s, Eigen::VectorXd& q) {
                             kin.data = s;
                             lma.CartToJnt(kin, f, kout);
                             q = kout.data;
                             return 0;
                           });

    // the same with equal weights on position and orientation errors (the default weights
    // 1, 1, 1, 0.01, 0.01, 0.01 stop at orientation errors of about 1e-3 rad)
    KDL::ChainIkSolverPos_LMA lma1(chain, Eigen::Matrix<double, 6, 1>::Ones());
    const Outcome lm1 = run(model, joints, targets, mid,
                            [&](const KDL::Frame& f, const Eigen::VectorXd& s, Eigen::VectorXd& q) {
                              kin.data = s;
                              lma1.CartToJnt(kin, f, kout);
                              q = kout.data;
                              return 0;
                            });

    auto row = [&](const char* solver_name, const Outcome& o, bool iters) {
      std::printf("%-9s %-26s %9.2f %9.4f %9.4f %9.3f ", c.name.c_str(), solver_name, o.success,
                  o.mean_ms, o.median_ms, o.max_ms);
      if (iters)
        std::printf("%7.1f ", o.mean_iterations);
      else
        std::printf("%7s ", "-");
      std::printf("%9.2fx %9.1e %9.1e %9.1e\n", nr.mean_ms / o.mean_ms, o.err_median, o.err_p99,
                  o.err_max);
    };
    row("mindyn IkSolver", ours, true);
    row("KDL ChainIkSolverPos_NR_JL", nr, false);
    row("KDL ChainIkSolverPos_LMA", lm, false);
    row("KDL LMA, unit weights", lm1, false);
    if (std::isfinite(c.published_success))
      std::printf("%-9s %-26s %9.2f %9.4f   (published; mindyn is %.1fx faster)\n", c.name.c_str(),
                  "TRAC-IK", c.published_success, c.published_ms, c.published_ms / ours.mean_ms);
    std::printf("\n");
  }
  return 0;
}
