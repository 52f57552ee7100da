// The homography of the Oxford graffiti pair (graf1 -> graf3, a change of viewpoint of about 40
// degrees) from corners matched between the two, against the data set's ground truth
// (H1to3p.xml) and against cv::findHomography on the same matches.
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <vector>

#include "epipole/calib/homography.hpp"
#include "test_data.hpp"

namespace epipole::calib {
namespace {

Eigen::Matrix3d eigen_of(const cv::Mat& m) {
  Eigen::Matrix3d H;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) H(r, c) = m.at<double>(r, c);
  }
  return H / H(2, 2);
}

// Mean and largest distance between where H and the truth send the pixels of a grid over graf1.
struct Transfer {
  double mean = 0, worst = 0;
};
Transfer transfer_error(const Eigen::Matrix3d& H, const Eigen::Matrix3d& truth, cv::Size size) {
  Transfer t;
  int n = 0;
  for (int y = 0; y <= size.height; y += 16) {
    for (int x = 0; x <= size.width; x += 16) {
      const Eigen::Vector2d p(x, y);
      const double e = (apply_homography(H, p) - apply_homography(truth, p)).norm();
      t.mean += e;
      t.worst = std::max(t.worst, e);
      ++n;
    }
  }
  t.mean /= n;
  return t;
}

TEST(HomographyReference, TheGraffitiPairAgainstItsTruthAndOpenCV) {
  const cv::Mat a = cv::imread(test::data_file("samples/graf1.png"), cv::IMREAD_GRAYSCALE);
  const cv::Mat b = cv::imread(test::data_file("samples/graf3.png"), cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(a.empty());
  ASSERT_FALSE(b.empty());
  cv::FileStorage truth_file(test::data_file("samples/H1to3p.xml"), cv::FileStorage::READ);
  cv::Mat truth_cv;
  truth_file["H13"] >> truth_cv;
  ASSERT_EQ(truth_cv.rows, 3);
  const Eigen::Matrix3d truth = eigen_of(truth_cv);

  // Corners and their descriptors (SIFT), matched both ways with Lowe's ratio test: the matches
  // a user's tool would have, wrong ones among them.
  const cv::Ptr<cv::SIFT> sift = cv::SIFT::create(3000);
  std::vector<cv::KeyPoint> ka, kb;
  cv::Mat da, db;
  sift->detectAndCompute(a, cv::noArray(), ka, da);
  sift->detectAndCompute(b, cv::noArray(), kb, db);
  cv::BFMatcher matcher(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(da, db, knn, 2);
  std::vector<Eigen::Vector2d> from, to;
  std::vector<cv::Point2f> from_cv, to_cv;
  for (const auto& m : knn) {
    if (m.size() < 2 || m[0].distance > 0.8f * m[1].distance) continue;
    const cv::KeyPoint& from_key = ka[static_cast<std::size_t>(m[0].queryIdx)];
    const cv::KeyPoint& to_key = kb[static_cast<std::size_t>(m[0].trainIdx)];
    const cv::Point2f p = from_key.pt;
    const cv::Point2f q = to_key.pt;
    from.emplace_back(p.x, p.y);
    to.emplace_back(q.x, q.y);
    from_cv.push_back(p);
    to_cv.push_back(q);
  }
  ASSERT_GT(from.size(), 100u);
  int wrong = 0;  // matches more than 3 px from the truth
  for (std::size_t i = 0; i < from.size(); ++i) {
    wrong += (apply_homography(truth, from[i]) - to[i]).norm() > 3 ? 1 : 0;
  }

  // The same inlier distance for both (ours by default: 2 px).
  const HomographyFit ours = find_homography(from, to);
  const Eigen::Matrix3d theirs =
      eigen_of(cv::findHomography(from_cv, to_cv, cv::RANSAC, HomographyOptions{}.inlier_px));
  const Transfer e_ours = transfer_error(ours.H, truth, a.size());
  const Transfer e_theirs = transfer_error(theirs, truth, a.size());
  std::printf(
      "graffiti 1->3: %zu matches (%d off the truth by more than 3 px); ours: %d inliers, rms %.3f "
      "px, %d samples, against the truth mean %.3f px, worst %.3f px; cv::findHomography: mean "
      "%.3f px, worst %.3f px\n",
      from.size(), wrong, ours.inlier_count, ours.rms_px, ours.iterations, e_ours.mean,
      e_ours.worst, e_theirs.mean, e_theirs.worst);
  EXPECT_LT(e_ours.mean, 1.0);
  EXPECT_LT(e_ours.worst, 3.0);
  EXPECT_LE(e_ours.mean, e_theirs.mean * 1.25 + 0.1)
      << "not worse than OpenCV's on the same matches";
  // Most matches the truth holds within the inlier distance are inliers.
  int right = 0;
  for (std::size_t i = 0; i < from.size(); ++i) {
    right += (apply_homography(truth, from[i]) - to[i]).norm() <= HomographyOptions{}.inlier_px;
  }
  EXPECT_GE(ours.inlier_count, right * 9 / 10) << right << " matches within the inlier distance";
}

}  // namespace
}  // namespace epipole::calib
