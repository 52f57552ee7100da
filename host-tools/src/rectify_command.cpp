// epipole rectify LEFT RIGHT --calib rig.yaml: a stereo pair rectified as the firmware does it
// (calib's fixed-point maps, vision::Rectifier).
#include <chrono>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "epipole/calib/calibration.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/firmware/stereo_rectification.hpp"
#include "stereo_preview.hpp"

namespace epipole::tools {

namespace {

struct RectifyOptions {
  std::string left;
  std::string right;
  std::string calibration;
  std::string out_left;
  std::string out_right;
  std::string preview;
  bool json = false;
};

void run_rectify(const RectifyOptions& options, const GlobalOptions& global) {
  const calib::StereoCalibration calibration = calib::load_calibration(options.calibration);
  const GrayImage left = load_gray(options.left);
  const GrayImage right = load_gray(options.right);
  const std::pair<const GrayImage*, const std::string*> images[] = {{&left, &options.left},
                                                                    {&right, &options.right}};
  for (const auto& [image, name] : images) {
    require(image->width() == calibration.width && image->height() == calibration.height, *name,
            ": image is ", image->width(), "x", image->height(), " but ", options.calibration,
            " calibrates ", calibration.width, "x", calibration.height, " images");
  }
  firmware::StereoRectifiers rectifiers =
      firmware::make_stereo_rectifiers(calibration, parse_simd_path(global.kernels));
  const auto start = std::chrono::steady_clock::now();
  const GrayView rectified_left = rectifiers.left.rectify(left.view());
  const GrayView rectified_right = rectifiers.right.rectify(right.view());
  const std::chrono::duration<double, std::milli> elapsed =
      std::chrono::steady_clock::now() - start;
  save_image(options.out_left, rectified_left);
  save_image(options.out_right, rectified_right);
  if (!options.preview.empty()) {
    const RgbImage picture = side_by_side_preview(rectified_left, rectified_right);
    save_image(options.preview, ImageView<const Rgb8>(picture.view()));
  }
  if (options.json) {
    const nlohmann::json summary = {
        {"image_size", {{"width", calibration.width}, {"height", calibration.height}}},
        {"kernels", to_string(rectifiers.left.simd_path())},
        {"ms", elapsed.count()},
        {"left", options.out_left},
        {"right", options.out_right},
        {"preview", options.preview.empty() ? nlohmann::json() : nlohmann::json(options.preview)}};
    std::cout << summary.dump(2) << "\n";
    return;
  }
  std::cout << "rectified a " << calibration.width << "x" << calibration.height << " pair ("
            << to_string(rectifiers.left.simd_path()) << ") in " << elapsed.count()
            << " ms: " << options.out_left << ", " << options.out_right << "\n";
}

}  // namespace

void add_rectify_command(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<RectifyOptions>();
  CLI::App* cmd = app.add_subcommand(
      "rectify", "Rectify a stereo pair with a calibration file, as the firmware does");
  cmd->add_option("left", options->left, "Left image (PNG, JPEG, PGM)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("right", options->right, "Right image")->required()->check(CLI::ExistingFile);
  cmd->add_option("--calib", options->calibration, "Calibration file (epipole calibrate -o)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out-left", options->out_left, "Rectified left image (.png or .pgm)")
      ->required();
  cmd->add_option("--out-right", options->out_right, "Rectified right image (.png or .pgm)")
      ->required();
  cmd->add_option("--preview", options->preview,
                  "Write both rectified images side by side with horizontal lines (.png)");
  cmd->add_flag("--json", options->json,
                "Print the summary as JSON: size, kernels, time and the files written");
  cmd->callback([options, &global] { run_rectify(*options, global); });
}

}  // namespace epipole::tools
