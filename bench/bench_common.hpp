// What the benchmarks of generated C share: callgrind's client requests (no-ops without the
// valgrind headers), timing implementations in turns, and compiling generated C into a shared
// object loaded with dlopen.
#pragma once

#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "mindyn/codegen/emit_c.hpp"

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#else  // no valgrind headers: the callgrind mode runs without client requests
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_STOP_INSTRUMENTATION
#define CALLGRIND_ZERO_STATS
#define CALLGRIND_DUMP_STATS_AT(label) ((void)(label))
#endif

namespace mindyn::bench {

// Mean time per call in ns, the best over repetitions (the least disturbed by other load on a
// shared machine). The implementations take turns within each repetition, so that a slow phase
// of the machine weighs on all of them alike rather than on whichever ran during it.
using Impl = std::pair<const char*, std::function<void(int)>>;  // name, loop body

inline std::vector<double> timeInTurns(const std::vector<Impl>& impls, int calls, int repetitions) {
  using Clock = std::chrono::steady_clock;
  std::vector<double> best(impls.size(), 1e300);
  for (int r = 0; r < repetitions; ++r)
    for (size_t k = 0; k < impls.size(); ++k) {
      const auto t0 = Clock::now();
      for (int i = 0; i < calls; ++i) impls[k].second(i);
      const double ns = std::chrono::duration<double, std::nano>(Clock::now() - t0).count() / calls;
      best[k] = std::min(best[k], ns);
    }
  return best;
}

// Callgrind mode: per implementation `warmup` calls, then `calls` calls bracketed by client
// requests and dumped as "ROBOT/implementation" (scripts/callgrind_per_call.sh reads them).
inline void callgrindEach(const std::string& robot, const std::vector<Impl>& impls, long calls,
                          int warmup) {
  for (const auto& [impl, body] : impls) {
    for (int i = 0; i < warmup; ++i) body(i);  // first-call effects stay out of the count
    const std::string label = robot + "/" + impl;
    CALLGRIND_START_INSTRUMENTATION;
    CALLGRIND_ZERO_STATS;
    for (long i = 0; i < calls; ++i) body(static_cast<int>(i));
    CALLGRIND_DUMP_STATS_AT(label.c_str());
    CALLGRIND_STOP_INSTRUMENTATION;
  }
}

// Writes generated C as WORK/FILE.h and WORK/FILE.c, compiles it with `cc -std=c99 FLAGS` into
// WORK/libFILE.so, loads it (the handle appended to `libs`) and returns the symbol `fn`; nullptr
// (with a message) on failure.
inline void* compiledSymbol(const codegen::CFiles& files, const std::string& work,
                            const std::string& file, const std::string& flags,
                            const std::string& fn, std::vector<void*>& libs) {
  std::ofstream(work + "/" + file + ".h") << files.header;
  std::ofstream(work + "/" + file + ".c") << files.source;
  const std::string so = work + "/lib" + file + ".so";
  const std::string cmd =
      "cc -std=c99 " + flags + " -fPIC -shared -o " + so + " " + work + "/" + file + ".c -lm";
  if (std::system(cmd.c_str()) != 0) {
    std::fprintf(stderr, "compiling the generated C failed: %s\n", cmd.c_str());
    return nullptr;
  }
  void* lib = dlopen(("./" + so).c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!lib) {
    std::fprintf(stderr, "dlopen: %s\n", dlerror());
    return nullptr;
  }
  libs.push_back(lib);
  return dlsym(lib, fn.c_str());
}

}  // namespace mindyn::bench
