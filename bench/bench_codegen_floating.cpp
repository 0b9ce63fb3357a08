// Floating-base inverse dynamics per call, in one process: the generated C (base parameters of
// the numerical method, compiled here with the system C compiler and loaded with dlopen), without
// contacts and with a contact wrench on every leaf link (a quadruped's feet) in world axes and in
// the links' own axes, beside Pinocchio's rnea (C++, header-only or linked from the pin wheel) on
// the same robot with a JointModelFreeFlyer root, without and with external forces (fext, the
// links' axes). Prints ns/call, ratios and the generated code's operation counts.
//
// usage: bench_codegen_floating URDF [URDF ...]   (quadrupeds: Solo12, Go1 of example-robot-data)
// Environment: MINDYN_BENCH_CC_FLAGS (default -O2) for the generated C; with
// MINDYN_BENCH_CALLGRIND=N (under valgrind --tool=callgrind --instr-atstart=no) it times nothing
// and makes N calls per robot and implementation instead, each bracketed by callgrind client
// requests and dumped as "robot/implementation".
#include <cstdio>
#include <cstdlib>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody.hpp>
#include <random>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "mindyn/base_parameters.hpp"
#include "mindyn/codegen/emit_c.hpp"
#include "mindyn/urdf.hpp"
#include "pinocchio_adapter.hpp"

using namespace mindyn;
using bench::Impl;

namespace {

// q, dq, ddq, p, tau; and with contacts q, dq, ddq, p, f, tau
using IdFn = void (*)(const double*, const double*, const double*, const double*, double*);
using IdContactFn = void (*)(const double*, const double*, const double*, const double*,
                             const double*, double*);

volatile double sink = 0;

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_codegen_floating URDF [URDF ...]\n");
    return 2;
  }
  const char* env = std::getenv("MINDYN_BENCH_CC_FLAGS");
  const std::string flags = env ? env : "-O2";
  const char* cg = std::getenv("MINDYN_BENCH_CALLGRIND");
  const long callgrind = cg ? std::atol(cg) : 0;
  const std::string work = "bench_codegen_floating_build";
  std::system(("mkdir -p " + work).c_str());
  if (callgrind == 0) {
    std::printf(
        "floating-base inverse dynamics, ns per call (best of 150 turns of 2000 calls each); "
        "generated C: cc %s\n",
        flags.c_str());
    std::printf("%-8s %3s %3s %3s | %9s %9s | %9s %9s %9s | %8s %8s | %s\n", "robot", "nq", "nv",
                "nc", "gen. C", "Pinocchio", "C f world", "C f local", "Pin fext", "Pin/genC",
                "fext/loc", "ops gen. C: mul add trig; with contacts (world, local)");
  }
  for (int a = 1; a < argc; ++a) {
    const Model model = loadUrdf(argv[a], "", "floating");
    const std::string name = model.name;
    const int n = model.nq(), nq = model.configSize(), nv = model.velocitySize();
    // contacts: every leaf link (no joint mounted on it)
    std::vector<int> leaves;
    for (int k = 0; k < n; ++k) {
      bool leaf = true;
      for (int j = 0; j < n; ++j) leaf = leaf && model.parent(j) != k;
      if (leaf) leaves.push_back(k);
    }
    const int nc = static_cast<int>(leaves.size());
    BaseOptions options;
    options.method = BaseMethod::Numerical;  // the one method for a floating base
    const BaseParameters bp = computeBaseParameters(model, options);
    const codegen::ParameterSet ps = codegen::baseParameterSet(model, bp);
    const std::vector<codegen::Function> id = {codegen::Function::InverseDynamics};
    // per robot: a library loaded again under its old name would confuse callgrind
    const std::string fb = "fb" + std::to_string(a);
    const auto plain = codegen::generateCode(model, ps, id, fb + "_bench");
    const auto world = codegen::generateCode(model, ps, id, fb + "_world", false, {},
                                             codegen::Objective::Operations, {leaves, true});
    const auto local = codegen::generateCode(model, ps, id, fb + "_local", false, {},
                                             codegen::Objective::Operations, {leaves, false});
    std::vector<void*> libs;
    const auto gen = reinterpret_cast<IdFn>(
        bench::compiledSymbol(codegen::emitC(plain, fb + "_bench.h"), work, fb + "_bench", flags,
                              fb + "_bench_inverse_dynamics", libs));
    const auto genW = reinterpret_cast<IdContactFn>(
        bench::compiledSymbol(codegen::emitC(world, fb + "_world.h"), work, fb + "_world", flags,
                              fb + "_world_inverse_dynamics", libs));
    const auto genL = reinterpret_cast<IdContactFn>(
        bench::compiledSymbol(codegen::emitC(local, fb + "_local.h"), work, fb + "_local", flags,
                              fb + "_local_inverse_dynamics", libs));
    if (!gen || !genW || !genL) return 1;
    const auto closeLibs = [&] {
      for (void* lib : libs) dlclose(lib);
    };

    // states: unit quaternions, joint angles, velocities, accelerations and contact wrenches
    const int S = 256;
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(-2.0, 2.0);
    std::vector<Eigen::VectorXd> Q(S, Eigen::VectorXd(nq)), DQ(S, Eigen::VectorXd(nv)),
        DDQ = DQ, F(S, Eigen::VectorXd(6 * nc));
    for (int s = 0; s < S; ++s) {
      for (int i = 0; i < nq; ++i) Q[s][i] = 0.75 * u(rng);
      Q[s].segment<4>(3).normalize();
      for (int i = 0; i < nv; ++i) {
        DQ[s][i] = u(rng);
        DDQ[s][i] = u(rng);
      }
      for (int i = 0; i < 6 * nc; ++i) F[s][i] = 10.0 * u(rng);
    }
    const Eigen::VectorXd pb = ps.values;
    Eigen::VectorXd tau(nv);

    // the joint models Pinocchio's URDF parser picks (RX, RY, RZ where the axis is one)
    pinocchio::Model pm = bench::toPinocchioModel(model, bench::PinocchioJoints::Specialized);
    pinocchio::Data pd(pm);
    // Pinocchio's external forces: per joint, in its frame (the link's frame of a URDF)
    std::vector<std::vector<pinocchio::Force>> fext(
        S,
        std::vector<pinocchio::Force>(static_cast<size_t>(pm.njoints), pinocchio::Force::Zero()));
    for (int s = 0; s < S; ++s)
      for (int c = 0; c < nc; ++c)
        fext[s][static_cast<size_t>(leaves[c] + 1)] =
            pinocchio::Force(F[s].segment<3>(6 * c), F[s].segment<3>(6 * c + 3));

    // agreement first: the generated C against Pinocchio, without and with (local) contacts
    double worst = 0;
    for (int s = 0; s < 8; ++s) {
      const Eigen::VectorXd ref = pinocchio::rnea(pm, pd, Q[s], DQ[s], DDQ[s]);
      gen(Q[s].data(), DQ[s].data(), DDQ[s].data(), pb.data(), tau.data());
      worst = std::max(worst, (tau - ref).norm() / ref.norm());
      const Eigen::VectorXd refF = pinocchio::rnea(pm, pd, Q[s], DQ[s], DDQ[s], fext[s]);
      genL(Q[s].data(), DQ[s].data(), DDQ[s].data(), pb.data(), F[s].data(), tau.data());
      worst = std::max(worst, (tau - refF).norm() / refF.norm());
    }
    if (worst > 1e-10) {
      std::fprintf(stderr, "%s: generated C and Pinocchio disagree (relative %g)\n", name.c_str(),
                   worst);
      return 1;
    }

    const std::vector<Impl> impls = {
        {"generated_c",
         [&](int i) {
           const int s = i % S;
           gen(Q[s].data(), DQ[s].data(), DDQ[s].data(), pb.data(), tau.data());
           sink = sink + tau[0];
         }},
        {"pinocchio",
         [&](int i) {
           const int s = i % S;
           sink = sink + pinocchio::rnea(pm, pd, Q[s], DQ[s], DDQ[s])[0];
         }},
        {"generated_c_contacts_world",
         [&](int i) {
           const int s = i % S;
           genW(Q[s].data(), DQ[s].data(), DDQ[s].data(), pb.data(), F[s].data(), tau.data());
           sink = sink + tau[0];
         }},
        {"generated_c_contacts_local",
         [&](int i) {
           const int s = i % S;
           genL(Q[s].data(), DQ[s].data(), DDQ[s].data(), pb.data(), F[s].data(), tau.data());
           sink = sink + tau[0];
         }},
        {"pinocchio_fext",
         [&](int i) {
           const int s = i % S;
           sink = sink + pinocchio::rnea(pm, pd, Q[s], DQ[s], DDQ[s], fext[s])[0];
         }},
    };
    if (callgrind > 0) {
      bench::callgrindEach(name, impls, callgrind, 2 * S);
      closeLibs();
      continue;
    }
    const std::vector<double> t = bench::timeInTurns(impls, 2000, 150);
    const auto& c = plain.functions[0].program.count;
    const auto& w = world.functions[0].program.count;
    const auto& l = local.functions[0].program.count;
    std::printf(
        "%-8s %3d %3d %3d | %9.1f %9.1f | %9.1f %9.1f %9.1f | %8.2f %8.2f | %ld %ld %ld; %ld %ld, "
        "%ld %ld\n",
        name.c_str(), nq, nv, nc, t[0], t[1], t[2], t[3], t[4], t[1] / t[0], t[4] / t[3], c.mul,
        c.add, c.trig, w.mul, w.add, l.mul, l.add);
    closeLibs();
  }
  return 0;
}
