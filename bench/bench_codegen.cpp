// Inverse dynamics per call, in one process: the generated C (base parameters, compiled here
// with the system C compiler and loaded with dlopen; sines and cosines inline, and again from
// math.h), the runtime base-parameter tape, our
// classical Newton-Euler, Pinocchio's rnea (C++, linked from the pin wheel) and KDL's
// ChainIdSolver_RNE. Prints ns/call, ratios and operation counts. Robots: PUMA 560, ZCR07S, the
// Staubli RX-90 (published operation counts of other generators exist for it) and UR5.
//
// usage: bench_codegen ROBOT_DIR [UR5_URDF] [CC_FLAGS]
// With MINDYN_BENCH_CALLGRIND=N in the environment (under valgrind --tool=callgrind
// --instr-atstart=no) it times nothing and makes N calls per robot and implementation instead,
// each bracketed by callgrind client requests and dumped as "robot/implementation".
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody.hpp>
#include <random>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "mindyn/base_dynamics.hpp"
#include "mindyn/codegen/emit_c.hpp"
#include "mindyn/description.hpp"
#include "mindyn/dynamics.hpp"
#include "mindyn/kinematics.hpp"
#include "mindyn/urdf.hpp"
#include "pinocchio_adapter.hpp"

using namespace mindyn;
using bench::Impl;

namespace {

using IdFn = void (*)(const double*, const double*, const double*, const double*, double*);

volatile double sink = 0;

// The Staubli RX-90 in Khalil's modified DH table (D3 = RL4 = 0.45 m), the robot of the published
// OpenSYMORO operation counts; the inertial values are invented (physical, no zeros).
Model rx90() {
  const char* table[6] = {"alpha: 0, d: 0, r: 0",    "alpha: -90, d: 0, r: 0",
                          "alpha: 0, d: 0.45, r: 0", "alpha: 90, d: 0, r: 0.45",
                          "alpha: -90, d: 0, r: 0",  "alpha: 90, d: 0, r: 0"};
  std::string yaml = "name: rx90\nconvention: mdh\nangle_unit: deg\njoints:\n";
  for (int k = 0; k < 6; ++k) {
    const double m = 6.0 - k, c = 0.01 * (k + 1), i = 0.01 * (6 - k);
    yaml += "  - {name: j" + std::to_string(k + 1) + ", theta: 0, " + table[k] +
            ", inertial: {mass: " + std::to_string(m) + ", com: [" + std::to_string(c) + ", " +
            std::to_string(-0.5 * c) + ", " + std::to_string(0.7 * c) +
            "], inertia: {xx: " + std::to_string(i) + ", yy: " + std::to_string(1.1 * i) +
            ", zz: " + std::to_string(0.9 * i) + ", xy: " + std::to_string(0.05 * i) +
            ", xz: " + std::to_string(-0.04 * i) + ", yz: " + std::to_string(0.03 * i) + "}}}\n";
  }
  return parseYaml(yaml, "rx90");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_codegen ROBOT_DIR [UR5_URDF] [CC_FLAGS]\n");
    return 2;
  }
  const std::string dir = argv[1];
  const std::string flags = argc > 3 ? argv[3] : "-O2";
  const char* cg = std::getenv("MINDYN_BENCH_CALLGRIND");
  const long callgrind = cg ? std::atol(cg) : 0;
  std::vector<std::pair<std::string, Model>> robots;
  robots.emplace_back("puma560", loadYaml(dir + "/puma560.yaml"));
  robots.emplace_back("zcr07s", loadYaml(dir + "/zcr07s.yaml"));
  robots.emplace_back("rx90", rx90());
  if (argc > 2 && std::string(argv[2]).size()) robots.emplace_back("ur5", loadUrdf(argv[2], ""));
  const std::string work = "bench_codegen_build";
  std::system(("mkdir -p " + work).c_str());

  if (callgrind == 0) {
    std::printf(
        "inverse dynamics, ns per call (best of 150 turns of 2000 calls each); generated C: cc "
        "%s\n",
        flags.c_str());
    std::printf("%-8s %9s %9s %9s %9s %9s %9s | %8s %8s | %s\n", "robot", "gen. C", "C libm",
                "base tape", "mindyn NE", "Pinocchio", "KDL", "Pin/genC", "KDL/genC",
                "ops gen. C base (classical): mul add trig");
  }
  for (auto& [name, model] : robots) {
    const int n = model.nq();
    const BaseParameters bp = computeBaseParameters(model);
    const codegen::ParameterSet ps = codegen::baseParameterSet(model, bp);
    const auto code =
        codegen::generateCode(model, ps, {codegen::Function::InverseDynamics}, name + "_bench");
    const auto classical = codegen::generate(model, codegen::classicalParameterSet(model, {}),
                                             codegen::Function::InverseDynamics);
    // The generated C twice: sines and cosines inline (the default) and from math.h.
    std::vector<void*> libs;
    const auto build = [&](const std::string& file, codegen::CTrig trig) -> IdFn {
      return reinterpret_cast<IdFn>(bench::compiledSymbol(codegen::emitC(code, file + ".h", trig),
                                                          work, file, flags,
                                                          name + "_bench_inverse_dynamics", libs));
    };
    const IdFn gen = build(name + "_bench", codegen::CTrig::Inline);
    const IdFn genLibm = build(name + "_bench_libm", codegen::CTrig::Libm);
    if (!gen || !genLibm) return 1;
    const auto closeLibs = [&] {
      for (void* lib : libs) dlclose(lib);
    };

    // states
    const int S = 256;
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(-2.0, 2.0);
    std::vector<Eigen::VectorXd> Q(S, Eigen::VectorXd(n)), DQ = Q, DDQ = Q;
    for (int s = 0; s < S; ++s)
      for (int k = 0; k < n; ++k) {
        Q[s][k] = 1.5 * u(rng);
        DQ[s][k] = u(rng);
        DDQ[s][k] = u(rng);
      }
    const Eigen::VectorXd pb = ps.values, pi = model.parameters();
    Eigen::VectorXd tau(n), ref(n);

    Data data(model);
    BaseDynamics bd(model, bp);
    pinocchio::Model pm = bench::toPinocchioModel(model);
    pinocchio::Data pd(pm);
    KDL::Chain chain = toKdlChain(model);
    KDL::ChainIdSolver_RNE kdl(
        chain, KDL::Vector(model.gravity.x(), model.gravity.y(), model.gravity.z()));
    KDL::JntArray kq(n), kdq(n), kddq(n), kt(n);
    KDL::Wrenches fext(chain.getNrOfSegments(), KDL::Wrench::Zero());

    // agreement first
    double worst = 0;
    for (int s = 0; s < 8; ++s) {
      inverseDynamics(model, data, Q[s], DQ[s], DDQ[s], pi, {}, ref);
      gen(Q[s].data(), DQ[s].data(), DDQ[s].data(), pb.data(), tau.data());
      worst = std::max(worst, (tau - ref).norm() / ref.norm());
      genLibm(Q[s].data(), DQ[s].data(), DDQ[s].data(), pb.data(), tau.data());
      worst = std::max(worst, (tau - ref).norm() / ref.norm());
      bd.inverseDynamics(Q[s], DQ[s], DDQ[s], pb, tau);
      worst = std::max(worst, (tau - ref).norm() / ref.norm());
      worst =
          std::max(worst, (pinocchio::rnea(pm, pd, Q[s], DQ[s], DDQ[s]) - ref).norm() / ref.norm());
      for (int k = 0; k < n; ++k) {
        kq(k) = Q[s][k];
        kdq(k) = DQ[s][k];
        kddq(k) = DDQ[s][k];
      }
      kdl.CartToJnt(kq, kdq, kddq, fext, kt);
      worst = std::max(worst, (kt.data - ref).norm() / ref.norm());
    }
    if (worst > 1e-8) {
      std::fprintf(stderr, "%s: implementations disagree (relative %g)\n", name.c_str(), worst);
      return 1;
    }

    // The six implementations, each a loop body over the fixed states.
    const std::vector<Impl> impls = {
        {"generated_c",
         [&](int i) {
           const int s = i % S;
           gen(Q[s].data(), DQ[s].data(), DDQ[s].data(), pb.data(), tau.data());
           sink = sink + tau[0];
         }},
        {"generated_c_libm",
         [&](int i) {
           const int s = i % S;
           genLibm(Q[s].data(), DQ[s].data(), DDQ[s].data(), pb.data(), tau.data());
           sink = sink + tau[0];
         }},
        {"base_tape",
         [&](int i) {
           const int s = i % S;
           bd.inverseDynamics(Q[s], DQ[s], DDQ[s], pb, tau);
           sink = sink + tau[0];
         }},
        {"mindyn_ne",
         [&](int i) {
           const int s = i % S;
           inverseDynamics(model, data, Q[s], DQ[s], DDQ[s], pi, {}, tau);
           sink = sink + tau[0];
         }},
        {"pinocchio",
         [&](int i) {
           const int s = i % S;
           sink = sink + pinocchio::rnea(pm, pd, Q[s], DQ[s], DDQ[s])[0];
         }},
        {"kdl",
         [&](int i) {
           const int s = i % S;
           for (int k = 0; k < n; ++k) {
             kq(k) = Q[s][k];
             kdq(k) = DQ[s][k];
             kddq(k) = DDQ[s][k];
           }
           kdl.CartToJnt(kq, kdq, kddq, fext, kt);
           sink = sink + kt(0);
         }},
    };
    if (callgrind > 0) {
      // One dump per implementation, "robot/implementation", for scripts/bench_codegen.
      bench::callgrindEach(name, impls, callgrind, 2 * S);
      closeLibs();
      continue;
    }
    const std::vector<double> t = bench::timeInTurns(impls, 2000, 150);
    const double tGen = t[0], tLibm = t[1], tTape = t[2], tNe = t[3], tPin = t[4], tKdl = t[5];
    const auto& c = code.functions[0].program.count;
    const auto& k = classical.program.count;
    std::printf(
        "%-8s %9.1f %9.1f %9.1f %9.1f %9.1f %9.1f | %8.2f %8.2f | %ld %ld %ld (%ld %ld %ld)\n",
        name.c_str(), tGen, tLibm, tTape, tNe, tPin, tKdl, tPin / tGen, tKdl / tGen, c.mul, c.add,
        c.trig, k.mul, k.add, k.trig);
    closeLibs();
  }
  return 0;
}
