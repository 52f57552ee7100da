// epipole bench: the bench of epipole/tools/bench.hpp as a subcommand of the desk tool.
#include <memory>

#include "commands.hpp"
#include "epipole/tools/bench.hpp"

namespace epipole::tools {

void add_bench_command(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<BenchOptions>();
  CLI::App* command = app.add_subcommand("bench", kBenchDescription);
  add_bench_options(*command, *options);
  command->callback([options, &global] { run_bench(*options, parse_simd_path(global.kernels)); });
}

}  // namespace epipole::tools
