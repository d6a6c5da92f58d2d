// KLU and CHOLMOD under KINSOL: the same curves to solver tolerance, with contact (active rows
// eliminated for the Cholesky), plasticity, unloading and separation.
#include <dlfcn.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iterator>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "indentsim/simulation/simulation.hpp"
#include "indentsim/base/worker_threads.hpp"
#include "test_support.hpp"

using namespace indentsim;
using indentsim::testing::shipped_case;

namespace {
std::vector<IncrementRecord> curve(const std::string& name, const std::vector<std::string>& overrides) {
  Simulation sim(shipped_case(name, overrides));
  std::vector<IncrementRecord> rows;
  sim.run([&](const IncrementRecord& r) { rows.push_back(r); });
  return rows;
}
}  // namespace

TEST(LinearSolvers, KluAndCholmodGiveTheSameCurve) {
  for (const char* name : {"elastic.toml", "paper.toml", "load_unload.toml"}) {
    SCOPED_TRACE(name);
    const std::vector<std::string> common{"mesh.contact_nodes=8"};
    auto with = [&](const char* linear) {
      auto o = common;
      o.push_back(std::string("solver.linear=") + linear);
      return curve(name, o);
    };
    const auto klu = with("klu"), cholmod = with("cholmod");
    ASSERT_EQ(klu.size(), cholmod.size());
    double peak = 0;
    for (const auto& r : klu) peak = std::max(peak, r.force);
    for (std::size_t k = 0; k < klu.size(); ++k) {
      EXPECT_NEAR(cholmod[k].force, klu[k].force, 1e-9 * peak) << "step " << k;
      EXPECT_EQ(cholmod[k].contact_nodes, klu[k].contact_nodes) << "step " << k;
    }
  }
}

TEST(LinearSolvers, AutoPicksCholmodForLargeMeshesOnly) {
  // The whole mesh in the Newton systems: "auto" looks at the size of the system it factors.
  Simulation small(shipped_case("elastic.toml", {"mesh.contact_nodes=3", "solver.linear=auto", "load.increments=1",
                                                 "solver.far_field=full"}));
  Simulation large(shipped_case("elastic.toml", {"mesh.contact_nodes=10", "solver.linear=auto", "load.increments=1",
                                                 "solver.far_field=full"}));
  ASSERT_LT(small.mesh().equations(), 1000);
  ASSERT_GT(large.mesh().equations(), 1000);
  EXPECT_EQ(small.linear_solver(), LinearSolverKind::klu);
  EXPECT_EQ(large.linear_solver(), LinearSolverKind::cholmod);
  small.run();
  large.run();
  EXPECT_EQ(large.symbolic_analyses(), 1);  // CHOLMOD analyses the fixed pattern once too
  EXPECT_GT(small.contact().force, 0.0);
  EXPECT_GT(large.contact().force, 0.0);
  // Condensed, the same large mesh leaves a system far below the crossover: KLU.
  Simulation condensed(shipped_case("elastic.toml", {"mesh.contact_nodes=10", "solver.linear=auto"}));
  ASSERT_TRUE(condensed.near_field().condensed);
  EXPECT_LT(condensed.system_unknowns(), 1000);
  EXPECT_EQ(condensed.linear_solver(), LinearSolverKind::klu);
}

TEST(ActiveSetCycling, ReturningToAnEarlierSetWithoutProgressIsACycle) {
  ActiveSetHistory h;
  EXPECT_FALSE(h.record(1, 1.0));
  EXPECT_FALSE(h.record(2, 0.5));
  EXPECT_FALSE(h.record(2, 0.1));  // staying on a set: converging
  EXPECT_FALSE(h.record(3, 0.4));
  EXPECT_TRUE(h.record(2, 0.45));  // back to set 2 with no real progress: 2, 3, 2
  h.clear();
  EXPECT_FALSE(h.record(1, 1.0));
  EXPECT_FALSE(h.record(2, 0.5));
  EXPECT_FALSE(h.record(1, 0.01));  // a node flipped back, but the residual fell 100x: progress
  h.clear();
  EXPECT_FALSE(h.record(1, 2.4e-2));
  EXPECT_FALSE(h.record(2, 6.5e-4));
  EXPECT_FALSE(h.record(1, 6.3e-3));  // an overshoot at the contact edge, at a quarter of the first visit
  EXPECT_TRUE(h.record(2, 6.0e-4));   // ... but coming back to set 2 without halving its residual cycles
}

// worker_threads.hpp: after a run, OpenBLAS (Debian's pthreads build, which CHOLMOD calls) runs
// on one thread unless the environment asked for more.
TEST(LinearSolvers, OneBlasThreadPerRunUnlessTheEnvironmentAsks) {
  using Getter = int (*)();
  const auto get = reinterpret_cast<Getter>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  if (!get) GTEST_SKIP() << "no OpenBLAS in this process";
  curve("elastic.toml", {"mesh.contact_nodes=6", "solver.linear=cholmod"});
  if (const char* asked = std::getenv("OPENBLAS_NUM_THREADS")) EXPECT_EQ(get(), std::atoi(asked));
  else EXPECT_EQ(get(), 1);
}

// worker_threads.hpp: OpenMP's settings are each thread's own, and CHOLMOD's regions ask for four
// threads explicitly: every thread that runs a simulation (here a second one, after the first
// thread's run) gets one OpenMP thread and dynamic adjustment, which bounds those regions.
TEST(LinearSolvers, EveryThreadThatRunsGetsOneOpenMpThread) {
  using Getter = int (*)();
  const auto max_threads = reinterpret_cast<Getter>(dlsym(RTLD_DEFAULT, "omp_get_max_threads"));
  const auto dynamic = reinterpret_cast<Getter>(dlsym(RTLD_DEFAULT, "omp_get_dynamic"));
  if (!max_threads || !dynamic) GTEST_SKIP() << "no OpenMP runtime in this process";
  if (std::getenv("OMP_NUM_THREADS") || std::getenv("OMP_DYNAMIC")) GTEST_SKIP() << "the environment sets OpenMP";
  curve("elastic.toml", {"mesh.contact_nodes=6", "solver.linear=cholmod"});
  int threads = 0, adjusted = 0;
  std::thread other([&] {
    curve("elastic.toml", {"mesh.contact_nodes=6", "solver.linear=cholmod"});
    threads = max_threads();
    adjusted = dynamic();
  });
  other.join();
  EXPECT_EQ(threads, 1);
  EXPECT_EQ(adjusted, 1);
}

// CMakeLists.txt links OpenBLAS ahead of Ceres' ATLAS: the BLAS routines CHOLMOD calls by name
// (its supernodal kernels: dgemm, dsyrk, dtrsm, dpotrf) are OpenBLAS's, not ATLAS's generic ones.
TEST(LinearSolvers, CholmodCallsOpenBlas) {
  for (const char* routine : {"dgemm_", "dsyrk_", "dtrsm_", "dpotrf_"}) {
    SCOPED_TRACE(routine);
    void* symbol = dlsym(RTLD_DEFAULT, routine);
    ASSERT_NE(symbol, nullptr);
    Dl_info info{};
    ASSERT_NE(dladdr(symbol, &info), 0);
    EXPECT_NE(std::string(info.dli_fname).find("openblas"), std::string::npos) << info.dli_fname;
  }
}

// worker_threads.hpp: the CLI stops OpenBLAS's idle workers at its start (they would spin through
// the run); afterwards the BLAS still serves CHOLMOD on the calling thread.
TEST(LinearSolvers, IdleOpenBlasWorkersStopAndTheBlasStillServesCholmod) {
  if (!dlsym(RTLD_DEFAULT, "blas_thread_shutdown_")) GTEST_SKIP() << "no OpenBLAS pthreads build in this process";
  if (const char* asked = std::getenv("OPENBLAS_NUM_THREADS"); asked && std::atoi(asked) > 1)
    GTEST_SKIP() << "the environment asks for BLAS threads";
  const auto threads = [] {
    return std::distance(std::filesystem::directory_iterator("/proc/self/task"), std::filesystem::directory_iterator{});
  };
  const auto before = threads();
  EXPECT_TRUE(stop_idle_blas_workers());
  if (std::thread::hardware_concurrency() > 1) {
    EXPECT_LT(threads(), before);  // one worker per further core
  }
  const auto cholmod = curve("elastic.toml", {"mesh.contact_nodes=6", "solver.linear=cholmod"});
  const auto klu = curve("elastic.toml", {"mesh.contact_nodes=6", "solver.linear=klu"});
  ASSERT_EQ(cholmod.size(), klu.size());
  for (std::size_t k = 0; k < klu.size(); ++k) EXPECT_NEAR(cholmod[k].force, klu[k].force, 1e-9 * klu.back().force);
}

// cholmod_common.hpp: orderings come from METIS, whose random generator is global.  Runs in two
// threads at once (Python threads, a run beside its error estimate's companions) must each give
// the curve of the same run alone, bit for bit: the orderings, and so the factorizations' rounding,
// may not depend on what another thread does.  Unserialized, two runs of power_law.toml in two
// threads differed from the run alone in 4 of 12 tries.
TEST(LinearSolvers, RunsInTwoThreadsRepeatTheRunAloneBitForBit) {
  const std::vector<std::string> overrides{"mesh.contact_nodes=14"};
  const auto alone = curve("power_law.toml", overrides);
  for (int round = 0; round < 3; ++round) {
    std::vector<IncrementRecord> first, second;
    std::thread a([&] { first = curve("power_law.toml", overrides); });
    std::thread b([&] { second = curve("power_law.toml", overrides); });
    a.join();
    b.join();
    for (const auto* run : {&first, &second}) {
      ASSERT_EQ(run->size(), alone.size());
      for (std::size_t k = 0; k < alone.size(); ++k) EXPECT_EQ((*run)[k].force, alone[k].force) << "increment " << k;
    }
  }
}
