#pragma once

#include <CLI/CLI.hpp>

namespace epipole::tools {

// Options every subcommand understands.
struct GlobalOptions {
  std::string kernels = "auto";  // auto | ref | neon | avx2
};

// Each subcommand lives in its own file and registers itself on the app.
void add_features_command(CLI::App& app, const GlobalOptions& global);
void add_disparity_command(CLI::App& app, const GlobalOptions& global);
void add_match_command(CLI::App& app, const GlobalOptions& global);
void add_calibrate_command(CLI::App& app, const GlobalOptions& global);
void add_rectify_command(CLI::App& app, const GlobalOptions& global);
void add_link_command(CLI::App& app, const GlobalOptions& global);
void add_sim_command(CLI::App& app, const GlobalOptions& global);
void add_detect_command(CLI::App& app, const GlobalOptions& global);
void add_cascade_compile_command(CLI::App& app, const GlobalOptions& global);
void add_bench_command(CLI::App& app, const GlobalOptions& global);
void add_eval_disparity_command(CLI::App& app, const GlobalOptions& global);
void add_view_command(CLI::App& app, const GlobalOptions& global);
void add_measure_command(CLI::App& app, const GlobalOptions& global);

}  // namespace epipole::tools
