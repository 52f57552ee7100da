// epipole: the host tool for people at a desk. One binary, one subcommand per job.
#include <exception>
#include <iostream>

#include "commands.hpp"
#include "epipole/core/error.hpp"
#include "epipole/firmware/build_info.hpp"

int main(int argc, char** argv) {
  using namespace epipole;
  CLI::App app{"Epipole stereo-vision tools: run the firmware's stages on image files.", "epipole"};
  app.set_version_flag("--version", firmware::build_info());
  app.require_subcommand(1);
  app.fallthrough();

  tools::GlobalOptions global;
  app.add_option("--kernels", global.kernels,
                 "Kernel path: auto, ref (scalar), neon (SIMDe on x86) or avx2 (x86)")
      ->check(CLI::IsMember({"auto", "ref", "reference", "neon", "avx2"}))
      ->capture_default_str();

  tools::add_features_command(app, global);
  tools::add_disparity_command(app, global);
  tools::add_eval_disparity_command(app, global);
  tools::add_match_command(app, global);
  tools::add_calibrate_command(app, global);
  tools::add_rectify_command(app, global);
  tools::add_link_command(app, global);
  tools::add_sim_command(app, global);
  tools::add_detect_command(app, global);
  tools::add_cascade_compile_command(app, global);
  tools::add_bench_command(app, global);
  tools::add_view_command(app, global);
  tools::add_measure_command(app, global);
  // The same exit statuses for every subcommand, said in every --help.
  constexpr const char* kExitStatus =
      "Exit status: 0 success, 1 failure (one line on standard error says why), 2 usage error.";
  app.footer(kExitStatus);
  for (CLI::App* command : app.get_subcommands({})) command->footer(kExitStatus);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int status = app.exit(e);  // prints the help, the version or the usage error
    return status == 0 ? 0 : 2;
  } catch (const Error& e) {
    std::cerr << "epipole: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "epipole: internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
