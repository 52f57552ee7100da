// OpenCV's stereo calibration files written by cv::FileStorage, as the stereo_calib sample
// writes them.
#include <opencv2/core.hpp>

#include <string>

#include "epipole/core/error.hpp"
#include "epipole/core/text_file.hpp"
#include "epipole/tools/opencv_calibration.hpp"
#include "epipole/tools/opencv_matrices.hpp"

namespace epipole::tools {

namespace {

// One YAML file's text, the keys written by `write` after the image size.
template <typename Write>
std::string yaml_storage(const calib::StereoCalibration& c, const std::filesystem::path& file,
                         Write write) {
  try {
    cv::FileStorage storage(".yml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
    storage << "image_width" << c.width << "image_height" << c.height;
    write(storage);
    return storage.releaseAndGetString();
  } catch (const cv::Exception& e) {
    throw Error(cat(file.string(), ": OpenCV cannot write it (", e.err, ")"));
  }
}

}  // namespace

void export_opencv_calibration(const calib::StereoCalibration& c,
                               const std::filesystem::path& directory) {
  calib::validate(c);
  make_directories(directory);
  const std::filesystem::path intrinsics = directory / "intrinsics.yml";
  write_text_file_atomically(intrinsics, yaml_storage(c, intrinsics, [&](cv::FileStorage& s) {
                               s << "M1" << opencv_matrix(c.left.camera_matrix());
                               s << "D1" << opencv_coefficients(c.left.camera.distortion);
                               s << "M2" << opencv_matrix(c.right.camera_matrix());
                               s << "D2" << opencv_coefficients(c.right.camera.distortion);
                             }));
  const std::filesystem::path extrinsics = directory / "extrinsics.yml";
  write_text_file_atomically(extrinsics, yaml_storage(c, extrinsics, [&](cv::FileStorage& s) {
                               s << "R" << opencv_matrix(c.R) << "T" << opencv_matrix(c.T);
                               s << "R1" << opencv_matrix(c.left.rectification);
                               s << "R2" << opencv_matrix(c.right.rectification);
                               s << "P1" << opencv_matrix(c.left.projection);
                               s << "P2" << opencv_matrix(c.right.projection);
                               s << "Q" << opencv_matrix(c.Q);
                             }));
}

}  // namespace epipole::tools
