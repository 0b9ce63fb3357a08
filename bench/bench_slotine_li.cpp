// Cost of the Slotine-Li regressor beside the ordinary regressor it generalises (same model, same
// layout, same states): ns per call and the ratio. Usage: bench_slotine_li [calls]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "mindyn/base_parameters.hpp"
#include "mindyn/description.hpp"
#include "mindyn/slotine_li.hpp"

using namespace mindyn;
using Clock = std::chrono::steady_clock;

template <class F>
double nsPerCall(int calls, F&& f) {
  double best = 1e300;
  for (int rep = 0; rep < 5; ++rep) {  // best of five: the least disturbed run
    const auto t0 = Clock::now();
    for (int i = 0; i < calls; ++i) f(i);
    best = std::min(best, std::chrono::duration<double, std::nano>(Clock::now() - t0).count());
  }
  return best / calls;
}

int main(int argc, char** argv) {
  const int calls = argc > 1 ? std::atoi(argv[1]) : 20000;
  std::printf("Slotine-Li regressor vs the regressor W(q, dq, ddq), ns per call (best of 5 x %d)\n",
              calls);
  std::printf("%-10s %-8s %12s %12s %8s %14s %14s\n", "robot", "layout", "W", "Y (S-L)", "Y/W",
              "W_b", "Y_b (S-L)");
  for (const char* name : {"puma560", "zcr07s", "stanford"}) {
    const Model model = loadYaml(std::string(MINDYN_ROBOT_DIR) + "/" + name + ".yaml");
    const int n = model.nq();
    for (ParameterLayout layout : {ParameterLayout{false, false}, ParameterLayout{true, true}}) {
      Data data(model);
      SlotineLiData sl(model, layout);
      BaseOptions o;
      o.layout = layout;
      const BaseParameters bp = computeBaseParameters(model, o);
      std::mt19937 rng(5);
      std::uniform_real_distribution<double> u(-1, 1);
      const int states = 64;
      std::vector<Eigen::VectorXd> x(4 * states, Eigen::VectorXd(n));
      for (auto& v : x)
        for (int k = 0; k < n; ++k) v[k] = u(rng);
      Eigen::MatrixXd W(n, layout.size(n)), Y(n, layout.size(n)), Wb(n, bp.eom.size()),
          Yb(n, bp.eom.size());
      double sink = 0;
      const double tw = nsPerCall(calls, [&](int i) {
        const int s = 4 * (i % states);
        regressor(model, data, x[s], x[s + 1], x[s + 2], layout, W);
        sink += W(0, 0);
      });
      const double ty = nsPerCall(calls, [&](int i) {
        const int s = 4 * (i % states);
        slotineLiRegressor(model, data, sl, x[s], x[s + 1], x[s + 3], x[s + 2], layout, Y);
        sink += Y(0, 0);
      });
      const double twb = nsPerCall(calls, [&](int i) {
        const int s = 4 * (i % states);
        baseRegressor(model, data, bp, x[s], x[s + 1], x[s + 2], W, Wb);
        sink += Wb(0, 0);
      });
      const double tyb = nsPerCall(calls, [&](int i) {
        const int s = 4 * (i % states);
        slotineLiBaseRegressor(model, data, sl, bp, x[s], x[s + 1], x[s + 3], x[s + 2], Yb);
        sink += Yb(0, 0);
      });
      std::printf("%-10s %-8s %12.0f %12.0f %7.2fx %14.0f %14.0f%s\n", name,
                  layout.rotor ? "+Ia,F" : "inertial", tw, ty, ty / tw, twb, tyb,
                  sink == 12345.678 ? " " : "");
    }
  }
  return 0;
}
