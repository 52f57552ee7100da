// epipole-bench: the bench of `epipole bench` as a program of its own, for a board (the desk
// tool's other commands need the host's libraries). Same options, same table and JSON.
#include <exception>
#include <iostream>

#include "epipole/core/error.hpp"
#include "epipole/firmware/build_info.hpp"
#include "epipole/tools/bench.hpp"

int main(int argc, char** argv) {
  using namespace epipole;
  CLI::App app{tools::kBenchDescription, "epipole-bench"};
  app.set_version_flag("--version", firmware::build_info());
  std::string kernels = "auto";
  app.add_option("--kernels", kernels, "Kernel path: auto, ref (scalar), neon or avx2 (x86)")
      ->check(CLI::IsMember({"auto", "ref", "reference", "neon", "avx2"}))
      ->capture_default_str();
  tools::BenchOptions options;
  tools::add_bench_options(app, options);
  app.footer(
      "Exit status: 0 success, 1 failure (one line on standard error says why), 2 usage error.");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int status = app.exit(e);  // prints the help, the version or the usage error
    return status == 0 ? 0 : 2;
  }
  try {
    tools::run_bench(options, parse_simd_path(kernels));
  } catch (const Error& e) {
    std::cerr << "epipole-bench: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "epipole-bench: internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
