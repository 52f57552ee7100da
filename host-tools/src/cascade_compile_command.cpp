// epipole cascade-compile IN.xml OUT.bin: OpenCV's cascade XML to the firmware's compact,
// versioned, checksummed binary (docs/vision.md, "The compiled cascade format").
#include <fstream>
#include <iostream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "epipole/core/error.hpp"
#include "epipole/tools/cascade_xml.hpp"

namespace epipole::tools {

namespace {

struct CompileOptions {
  std::string in;
  std::string out;
};

void run_compile(const CompileOptions& options) {
  const vision::CascadeModel model = load_cascade(options.in);
  const std::vector<std::uint8_t> bytes = model.to_binary();
  // The file must read back as the same cascade before it is kept.
  require(vision::CascadeModel::from_binary(bytes, options.out).data() == model.data(), options.out,
          ": the compiled cascade does not read back as the input");
  std::ofstream out(options.out, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  out.close();
  require(static_cast<bool>(out), options.out, ": cannot write");
  std::cout << options.in << ": " << to_string(model.feature_type()) << " " << model.window_width()
            << "x" << model.window_height() << ", " << model.stage_count() << " stages, "
            << model.weak_count() << " weak classifiers ("
            << (model.stump_based() ? "stumps" : "trees") << "), " << model.feature_count()
            << " features" << (model.has_tilted_features() ? " (some tilted)" : "") << " -> "
            << options.out << " (" << bytes.size() << " bytes)\n";
}

}  // namespace

void add_cascade_compile_command(CLI::App& app, const GlobalOptions& /*global*/) {
  auto options = std::make_shared<CompileOptions>();
  CLI::App* cmd = app.add_subcommand(
      "cascade-compile", "Compile an OpenCV cascade XML into the firmware's binary format");
  cmd->add_option("in", options->in, "OpenCV cascade XML (traincascade format)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("out", options->out, "Compiled cascade to write (.bin)")->required();
  cmd->callback([options] { run_compile(*options); });
}

}  // namespace epipole::tools
