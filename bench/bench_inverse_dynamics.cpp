// Inverse dynamics, ns per call, in one process: mindyn::inverseDynamics (classical parameters)
// beside Pinocchio's rnea and KDL's ChainIdSolver_RNE, on the same robots. The Pinocchio and KDL
// models are built from the mindyn::Model (pinocchio_adapter.hpp, mindyn::toKdlChain), and the
// three torque vectors are checked to agree before anything is timed.
//
//   bench_inverse_dynamics [--reps N] [--min-time-ms T] [--robot-data DIR] [--ir FILE]
//   bench_inverse_dynamics --callgrind N     (under valgrind --tool=callgrind --instr-atstart=no)
//
// Timing: per robot and library, repetitions of a loop cycling through 64 fixed random states;
// each repetition runs for at least T ms (steady_clock); the table gives the median over N
// repetitions (the libraries are interleaved repetition by repetition) and the interquartile
// range. On a shared machine, repetitions during which the process was preempted (involuntary
// context switch, getrusage) are run again, up to 10 N rounds.
// Callgrind mode: N calls per robot and library, each bracketed by callgrind client requests and
// dumped as "robot/library"; scripts/bench turns the dumps into instructions per call and feeds
// them back with --ir FILE (lines "robot library instructions_per_call").
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <map>
#include <pinocchio/algorithm/rnea.hpp>
#include <random>
#include <string>
#include <vector>

#include "mindyn/description.hpp"
#include "mindyn/dynamics.hpp"
#include "mindyn/kinematics.hpp"
#include "mindyn/urdf.hpp"
#include "pinocchio_adapter.hpp"

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#else  // no valgrind headers: callgrind mode still runs, without client requests
#define RUNNING_ON_VALGRIND 0
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_STOP_INSTRUMENTATION
#define CALLGRIND_ZERO_STATS
#define CALLGRIND_DUMP_STATS_AT(label) ((void)(label))
#endif

#ifndef MINDYN_ROBOT_DIR
#error "MINDYN_ROBOT_DIR must name python/mindyn/robots"
#endif
#ifndef MINDYN_ROBOT_DATA_DIR
#define MINDYN_ROBOT_DATA_DIR ""
#endif
#ifndef MINDYN_BENCH_COMPILER
#define MINDYN_BENCH_COMPILER "?"
#endif
#ifndef MINDYN_BENCH_KDL_VERSION
#define MINDYN_BENCH_KDL_VERSION "?"
#endif
#ifdef PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION
#define MINDYN_BENCH_PINOCCHIO_MODE "rnea from libpinocchio_default"
#else
#define MINDYN_BENCH_PINOCCHIO_MODE "header-only, compiled here"
#endif

namespace {

constexpr int kSamples = 64;  // power of two: index = i & (kSamples - 1)
constexpr double kTolerance = 1e-9;

[[noreturn]] void fail(const std::string& message) {
  std::fprintf(stderr, "bench_inverse_dynamics: %s\n", message.c_str());
  std::exit(2);
}

// Keeps the compiler from dropping a result.
template <class T>
inline void keep(const T& value) {
  asm volatile("" : : "g"(&value) : "memory");
}

struct State {
  Eigen::VectorXd q, dq, ddq;
  KDL::JntArray kq, kdq, kddq;
};

// One library's inverse dynamics on one robot, with its own workspace.
struct Runner {
  std::string library;
  std::function<void(int)> call;            // computes the torques of sample i
  std::function<Eigen::VectorXd()> result;  // the torques of the last call
  std::function<void(long)> loop;           // n calls, cycling through the samples
};

template <class F>
std::function<void(long)> makeLoop(F f) {
  return [f](long n) mutable {
    for (long i = 0; i < n; ++i) f(static_cast<int>(i & (kSamples - 1)));
  };
}

struct Robot {
  std::string name;
  mindyn::Model model;
  std::vector<State> states;

  // Workspaces; heap objects so that the runners' references stay valid.
  std::unique_ptr<mindyn::Data> md;
  Eigen::VectorXd params, tau;
  std::unique_ptr<pinocchio::Model> pm, pm_spec;
  std::unique_ptr<pinocchio::Data> pd, pd_spec;
  std::unique_ptr<KDL::Chain> chain;
  std::unique_ptr<KDL::ChainIdSolver_RNE> kdl;
  KDL::Wrenches wrenches;
  KDL::JntArray ktau;

  std::vector<Runner> runners;
};

std::unique_ptr<Robot> makeRobot(const std::string& name, mindyn::Model model) {
  auto r = std::make_unique<Robot>();
  r->name = name;
  r->model = std::move(model);
  const mindyn::Model& m = r->model;
  const int n = m.nq();

  std::mt19937 rng(20240601u + static_cast<unsigned>(n));
  std::uniform_real_distribution<double> uq(-M_PI, M_PI), udq(-2.0, 2.0), uddq(-4.0, 4.0);
  for (int s = 0; s < kSamples; ++s) {
    State st;
    st.q.resize(n);
    st.dq.resize(n);
    st.ddq.resize(n);
    for (int k = 0; k < n; ++k) {
      st.q[k] = uq(rng);
      st.dq[k] = udq(rng);
      st.ddq[k] = uddq(rng);
    }
    st.kq.resize(n);
    st.kdq.resize(n);
    st.kddq.resize(n);
    st.kq.data = st.q;
    st.kdq.data = st.dq;
    st.kddq.data = st.ddq;
    r->states.push_back(std::move(st));
  }

  Robot* p = r.get();
  // mindyn: classical parameters, default layout (no rotor inertia, no friction).
  p->md = std::make_unique<mindyn::Data>(m);
  p->params = m.parameters();
  p->tau = Eigen::VectorXd::Zero(n);
  auto mindyn_call = [p](int i) {
    const State& s = p->states[i];
    mindyn::inverseDynamics(p->model, *p->md, s.q, s.dq, s.ddq, p->params, {}, p->tau);
    keep(p->tau[0]);
  };
  p->runners.push_back({"mindyn", mindyn_call, [p] { return p->tau; }, makeLoop(mindyn_call)});

  // Pinocchio, built from the mindyn model: unaligned joints (the reference) ...
  p->pm = std::make_unique<pinocchio::Model>(
      mindyn::bench::toPinocchioModel(m, mindyn::bench::PinocchioJoints::Unaligned));
  p->pd = std::make_unique<pinocchio::Data>(*p->pm);
  auto pin_call = [p](int i) {
    const State& s = p->states[i];
    pinocchio::rnea(*p->pm, *p->pd, s.q, s.dq, s.ddq);
    keep(p->pd->tau[0]);
  };
  p->runners.push_back(
      {"pinocchio", pin_call, [p] { return Eigen::VectorXd(p->pd->tau); }, makeLoop(pin_call)});

  // ... and with RX/RY/RZ joints where the axis allows, as Pinocchio's URDF parser builds it.
  p->pm_spec = std::make_unique<pinocchio::Model>(
      mindyn::bench::toPinocchioModel(m, mindyn::bench::PinocchioJoints::Specialized));
  p->pd_spec = std::make_unique<pinocchio::Data>(*p->pm_spec);
  auto spec_call = [p](int i) {
    const State& s = p->states[i];
    pinocchio::rnea(*p->pm_spec, *p->pd_spec, s.q, s.dq, s.ddq);
    keep(p->pd_spec->tau[0]);
  };
  p->runners.push_back({"pinocchio-spec", spec_call,
                        [p] { return Eigen::VectorXd(p->pd_spec->tau); }, makeLoop(spec_call)});

  // KDL: the chain mindyn builds, gravity of the model, no external wrenches.
  p->chain = std::make_unique<KDL::Chain>(mindyn::toKdlChain(m));
  const Eigen::Vector3d g = m.gravity;
  p->kdl = std::make_unique<KDL::ChainIdSolver_RNE>(*p->chain, KDL::Vector(g.x(), g.y(), g.z()));
  p->wrenches.assign(p->chain->getNrOfSegments(), KDL::Wrench::Zero());
  p->ktau.resize(n);
  auto kdl_call = [p](int i) {
    const State& s = p->states[i];
    p->kdl->CartToJnt(s.kq, s.kdq, s.kddq, p->wrenches, p->ktau);
    keep(p->ktau(0));
  };
  p->runners.push_back(
      {"kdl", kdl_call, [p] { return Eigen::VectorXd(p->ktau.data); }, makeLoop(kdl_call)});
  return r;
}

// All libraries must give the same torques (mindyn is the reference of the comparison).
void verify(Robot& r) {
  double worst = 0.0;
  std::string worst_library;
  for (int i = 0; i < kSamples; ++i) {
    r.runners[0].call(i);
    const Eigen::VectorXd ref = r.runners[0].result();
    const double scale = ref.cwiseAbs().maxCoeff();
    if (!std::isfinite(scale) || scale == 0.0)
      fail(r.name + ": mindyn torques are zero or not finite at sample " + std::to_string(i));
    for (size_t l = 1; l < r.runners.size(); ++l) {
      r.runners[l].call(i);
      const Eigen::VectorXd t = r.runners[l].result();
      const double err = (t - ref).cwiseAbs().maxCoeff() / scale;
      if (!(err <= kTolerance)) {
        char buf[256];
        std::snprintf(buf, sizeof buf,
                      "%s: %s and mindyn disagree at sample %d: max |dtau| / max |tau| = %.3g "
                      "(tolerance %.0e)",
                      r.name.c_str(), r.runners[l].library.c_str(), i, err, kTolerance);
        fail(buf);
      }
      if (err > worst) {
        worst = err;
        worst_library = r.runners[l].library;
      }
    }
  }
  std::printf(
      "check %-8s %d joints: torques of %zu libraries agree on %d states, worst %.1e (%s)\n",
      r.name.c_str(), r.model.nq(), r.runners.size(), kSamples, worst, worst_library.c_str());
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double quantile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  const double x = p * (v.size() - 1);
  const size_t i = static_cast<size_t>(x);
  if (i + 1 >= v.size()) return v.back();
  return v[i] + (x - i) * (v[i + 1] - v[i]);
}

// Wall time of `calls` calls, and whether the scheduler took the CPU away meanwhile
// (involuntary context switches: another process ran on this CPU during the measurement).
struct Timed {
  double seconds;
  bool preempted;
};

Timed timeLoop(const std::function<void(long)>& loop, long calls) {
  rusage u0{}, u1{};
  getrusage(RUSAGE_THREAD, &u0);
  const auto t0 = std::chrono::steady_clock::now();
  loop(calls);
  const auto t1 = std::chrono::steady_clock::now();
  getrusage(RUSAGE_THREAD, &u1);
  return {std::chrono::duration<double>(t1 - t0).count(), u1.ru_nivcsw != u0.ru_nivcsw};
}

struct Args {
  int reps = 21;
  double min_time_ms = 2.0;
  long callgrind = 0;
  std::string robot_data = MINDYN_ROBOT_DATA_DIR;
  std::string ir_file;
};

Args parseArgs(int argc, char** argv) {
  Args a;
  auto value = [&](int& i) -> std::string {
    if (i + 1 >= argc) fail(std::string("option ") + argv[i] + " needs a value");
    return argv[++i];
  };
  for (int i = 1; i < argc; ++i) {
    const std::string opt = argv[i];
    if (opt == "--reps") {
      a.reps = std::atoi(value(i).c_str());
    } else if (opt == "--min-time-ms") {
      a.min_time_ms = std::atof(value(i).c_str());
    } else if (opt == "--callgrind") {
      a.callgrind = std::atol(value(i).c_str());
    } else if (opt == "--robot-data") {
      a.robot_data = value(i);
    } else if (opt == "--ir") {
      a.ir_file = value(i);
    } else if (opt == "-h" || opt == "--help") {
      std::printf(
          "usage: %s [--reps N] [--min-time-ms T] [--robot-data DIR] [--ir FILE] "
          "[--callgrind N]\n",
          argv[0]);
      std::exit(0);
    } else {
      fail("unknown option " + opt + " (see --help)");
    }
  }
  if (a.reps < 1 || a.min_time_ms <= 0.0 || a.callgrind < 0) fail("bad option value");
  return a;
}

std::vector<std::unique_ptr<Robot>> loadRobots(const Args& args) {
  if (args.robot_data.empty())
    fail(
        "no example-robot-data folder: pass --robot-data "
        "<site-packages>/cmeel.prefix/share/example-robot-data/robots");
  const std::string ur5 = args.robot_data + "/ur_description/urdf/ur5_robot.urdf";
  const std::string panda = args.robot_data + "/panda_description/urdf/panda.urdf";
  std::vector<std::unique_ptr<Robot>> robots;
  try {
    robots.push_back(makeRobot("puma560", mindyn::loadYaml(MINDYN_ROBOT_DIR "/puma560.yaml")));
    robots.push_back(makeRobot("ur5", mindyn::loadUrdf(ur5)));
    robots.push_back(makeRobot("panda", mindyn::loadUrdf(panda, "panda_link8")));
  } catch (const std::exception& e) {
    fail(std::string("loading the robots: ") + e.what());
  }
  return robots;
}

// Callgrind mode: a fixed number of calls per robot and library, one dump each.
void runCallgrind(std::vector<std::unique_ptr<Robot>>& robots, long calls) {
  if (!RUNNING_ON_VALGRIND)
    std::printf("note: not running under valgrind; the client requests do nothing\n");
  for (auto& r : robots) {
    for (auto& run : r->runners) {
      run.loop(2 * kSamples);  // warm up: first-call effects stay out of the count
      const std::string label = r->name + "/" + run.library;
      CALLGRIND_START_INSTRUMENTATION;
      CALLGRIND_ZERO_STATS;
      run.loop(calls);
      CALLGRIND_DUMP_STATS_AT(label.c_str());
      CALLGRIND_STOP_INSTRUMENTATION;
    }
  }
  std::printf("callgrind: %ld calls per robot and library dumped as robot/library\n", calls);
}

std::map<std::string, double> readIr(const std::string& path) {
  std::map<std::string, double> ir;
  if (path.empty()) return ir;
  std::ifstream in(path);
  if (!in) fail("cannot read " + path);
  std::string robot, library;
  double value;
  while (in >> robot >> library >> value) ir[robot + "/" + library] = value;
  return ir;
}

// Timings on a shared machine: say how busy it is.
void printMachine() {
  double load = -1.0;
  if (std::FILE* f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf", &load) != 1) load = -1.0;
    std::fclose(f);
  }
  const long cpus = sysconf(_SC_NPROCESSORS_ONLN);
  std::printf("machine: %ld CPUs, load average (1 min) %.2f%s\n", cpus, load,
              load > 0.5 * cpus ? "  -- busy: timings are noisy, compare ratios and Ir/call" : "");
}

void runTiming(std::vector<std::unique_ptr<Robot>>& robots, const Args& args) {
  const auto ir = readIr(args.ir_file);
  std::printf("\nbuild: %s; Pinocchio %s (%s); Eigen %d.%d.%d; KDL %s (Debian build)\n",
              MINDYN_BENCH_COMPILER, PINOCCHIO_VERSION, MINDYN_BENCH_PINOCCHIO_MODE,
              EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION,
              MINDYN_BENCH_KDL_VERSION);
  printMachine();
  std::printf(
      "ns/call: median of %d repetitions of >= %.1f ms per robot and library (steady_clock), "
      "libraries interleaved;\nrepetitions during which the process was preempted are retried "
      "(reps = kept/run; '!' = too few clean ones, all kept)\n\n",
      args.reps, args.min_time_ms);
  std::printf("%-8s %-15s %9s %6s %8s %8s %8s %9s\n", "robot", "library", "ns/call", "IQR%", "reps",
              "vs pin", "vs KDL", "Ir/call");
  std::printf("%s\n", std::string(78, '-').c_str());
  const int max_rounds = 10 * args.reps;
  for (auto& r : robots) {
    const size_t nl = r->runners.size();
    // Calls per repetition so that one repetition takes at least min_time_ms.
    std::vector<long> calls(nl);
    for (size_t l = 0; l < nl; ++l) {
      r->runners[l].loop(1000);  // warm up
      long c = 64;
      while (timeLoop(r->runners[l].loop, c).seconds * 1e3 < args.min_time_ms / 4) c *= 2;
      calls[l] = 4 * c;
    }
    std::vector<std::vector<double>> clean(nl), all(nl);
    int rounds = 0;
    auto done = [&] {
      for (const auto& c : clean)
        if (static_cast<int>(c.size()) < args.reps) return false;
      return true;
    };
    while (rounds < max_rounds && !done()) {
      ++rounds;
      for (size_t l = 0; l < nl; ++l) {
        const Timed t = timeLoop(r->runners[l].loop, calls[l]);
        const double ns = t.seconds * 1e9 / calls[l];
        all[l].push_back(ns);
        if (!t.preempted && static_cast<int>(clean[l].size()) < args.reps) clean[l].push_back(ns);
      }
    }
    const int min_clean = std::min(args.reps, 5);
    std::vector<std::vector<double>*> used(nl);
    std::vector<double> med(nl);
    for (size_t l = 0; l < nl; ++l) {
      used[l] = static_cast<int>(clean[l].size()) >= min_clean ? &clean[l] : &all[l];
      med[l] = median(*used[l]);
    }
    const double pin = med[1], kdl = med[nl - 1];
    for (size_t l = 0; l < nl; ++l) {
      const std::vector<double>& v = *used[l];
      const double iqr = (quantile(v, 0.75) - quantile(v, 0.25)) / med[l] * 100.0;
      char reps[32];
      std::snprintf(reps, sizeof reps, "%zu/%d%s", v.size(), rounds, used[l] == &all[l] ? "!" : "");
      const auto it = ir.find(r->name + "/" + r->runners[l].library);
      char irs[32] = "-";
      if (it != ir.end()) std::snprintf(irs, sizeof irs, "%.0f", it->second);
      std::printf("%-8s %-15s %9.1f %5.1f%% %8s %7.2fx %7.2fx %9s\n", l ? "" : r->name.c_str(),
                  r->runners[l].library.c_str(), med[l], iqr, reps, med[l] / pin, med[l] / kdl,
                  irs);
    }
  }
  std::printf(
      "\npinocchio      = pinocchio::rnea on the model built from mindyn's "
      "(RevoluteUnaligned joints)\n"
      "pinocchio-spec = the same with RX/RY/RZ joints where the axis is +x/+y/+z, as "
      "Pinocchio's URDF parser builds\n"
      "vs pin / vs KDL = ns/call divided by pinocchio's / kdl's on the same robot; Ir/call = "
      "instructions per call under callgrind\n");
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = parseArgs(argc, argv);
  auto robots = loadRobots(args);
  for (auto& r : robots) verify(*r);
  if (args.callgrind > 0)
    runCallgrind(robots, args.callgrind);
  else
    runTiming(robots, args);
  return 0;
}
