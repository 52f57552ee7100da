// epipole_bench: every kernel beside OpenCV in one process, one thread. Benchmarks are named
// "<stage>/<implementation>/<arguments...>"; after the usual table, a summary prints each
// implementation's time as a ratio of OpenCV's for the same stage and arguments.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "epipole/core/simd.hpp"

namespace {

class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs) {
      if (run.run_type != Run::RT_Iteration || run.error_occurred) continue;
      const std::string name = run.benchmark_name();
      const auto first = name.find('/');
      if (first == std::string::npos) continue;
      const auto second = name.find('/', first + 1);
      const std::string implementation = name.substr(first + 1, second - first - 1);
      const std::string arguments = second == std::string::npos ? "" : name.substr(second);
      const double seconds =
          run.GetAdjustedRealTime() / benchmark::GetTimeUnitMultiplier(run.time_unit);
      times_[name.substr(0, first) + arguments][implementation] = seconds;
    }
  }

  void Finalize() override {
    ConsoleReporter::Finalize();
    std::printf("\n%-28s %-12s %12s %12s %8s\n", "stage/size", "ours", "ours (ms)", "opencv (ms)",
                "ratio");
    for (const auto& [stage, implementations] : times_) {
      const auto opencv = implementations.find("opencv");
      if (opencv == implementations.end()) continue;
      for (const auto& [implementation, time] : implementations) {
        if (implementation == "opencv") continue;
        std::printf("%-28s %-12s %12.3f %12.3f %8.2f\n", stage.c_str(), implementation.c_str(),
                    time * 1e3, opencv->second * 1e3, time / opencv->second);
      }
    }
  }

 private:
  std::map<std::string, std::map<std::string, double>> times_;  // stage/args -> impl -> s
};

}  // namespace

int main(int argc, char** argv) {
  cv::setNumThreads(1);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  std::printf("epipole kernels: %s; OpenCV %s, 1 thread\n", epipole::simd_description().c_str(),
              CV_VERSION);
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
