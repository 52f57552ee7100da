// Perspective-three-point and absolute orientation (p3p.hpp).
//
// Grunert's solution, in Haralick et al.'s notation: the points P1, P2, P3 lie at unknown
// distances s1, s2, s3 along the unit rays j1, j2, j3. With a = |P2 - P3|, b = |P1 - P3|,
// c = |P1 - P2| and the cosines of the angles between the rays, cos(alpha) = j2.j3,
// cos(beta) = j1.j3, cos(gamma) = j1.j2, the law of cosines gives three equations in s1..s3.
// With u = s2 / s1 and v = s3 / s1 they become a quartic in v; each of its real roots gives u,
// then s1 = b / sqrt(1 + v^2 - 2 v cos(beta)), s2 = u s1, s3 = v s1.
#include "epipole/calib/p3p.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <complex>

namespace epipole::calib {

int real_quartic_roots(const std::array<double, 5>& c, std::array<double, 4>& roots) {
  // The companion matrix of the monic polynomial: its eigenvalues are the roots.
  Eigen::Matrix4d companion = Eigen::Matrix4d::Zero();
  for (int i = 0; i < 4; ++i) companion(0, i) = -c[static_cast<std::size_t>(3 - i)] / c[4];
  companion(1, 0) = companion(2, 1) = companion(3, 2) = 1;
  const Eigen::EigenSolver<Eigen::Matrix4d> solver(companion, false);
  if (solver.info() != Eigen::Success) return 0;
  const auto value = [&](double x) {
    return (((c[4] * x + c[3]) * x + c[2]) * x + c[1]) * x + c[0];
  };
  const auto slope = [&](double x) {
    return ((4 * c[4] * x + 3 * c[3]) * x + 2 * c[2]) * x + c[1];
  };
  int n = 0;
  for (int i = 0; i < 4; ++i) {
    const std::complex<double> z = solver.eigenvalues()[i];
    // Near-double roots (a pose on the danger cylinder) come out as a complex pair with a small
    // imaginary part: taken as real, Newton decides.
    if (std::abs(z.imag()) > 1e-6 * std::max(1.0, std::abs(z.real()))) continue;
    double x = z.real();
    for (int k = 0; k < 3; ++k) {
      const double d = slope(x);
      if (d == 0) break;
      x -= value(x) / d;
    }
    roots[static_cast<std::size_t>(n++)] = x;
  }
  return n;
}

RigidMotion align_points(const Eigen::Vector3d* from, const Eigen::Vector3d* to, int n) {
  Eigen::Vector3d from_mean = Eigen::Vector3d::Zero(), to_mean = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    from_mean += from[i];
    to_mean += to[i];
  }
  from_mean /= n;
  to_mean /= n;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) covariance += (to[i] - to_mean) * (from[i] - from_mean).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance,
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  RigidMotion m;
  m.rotation = svd.matrixU() * d * svd.matrixV().transpose();
  m.translation = to_mean - m.rotation * from_mean;
  return m;
}

int solve_p3p(const std::array<Eigen::Vector3d, 3>& p, const std::array<Eigen::Vector3d, 3>& j,
              std::array<RigidMotion, 4>& poses) {
  const double aa = (p[1] - p[2]).squaredNorm();
  const double bb = (p[0] - p[2]).squaredNorm();
  const double cc = (p[0] - p[1]).squaredNorm();
  // Coincident or collinear points: no triangle to fit.
  if (aa == 0 || bb == 0 || cc == 0 ||
      (p[1] - p[0]).cross(p[2] - p[0]).squaredNorm() <
          1e-18 * std::max({aa, bb, cc}) * std::max({aa, bb, cc})) {
    return 0;
  }
  const double ca = j[1].dot(j[2]), cb = j[0].dot(j[2]), cg = j[0].dot(j[1]);
  const double caca = ca * ca, cbcb = cb * cb, cgcg = cg * cg;
  const double q1 = (aa - cc) / bb;  // Haralick et al.'s (a^2 - c^2) / b^2, and so on
  const double q2 = (aa + cc) / bb;
  const double q3 = (bb - cc) / bb;
  const double q4 = (bb - aa) / bb;
  std::array<double, 5> c{};
  c[4] = (q1 - 1) * (q1 - 1) - 4 * cc / bb * caca;
  c[3] = 4 * (q1 * (1 - q1) * cb - (1 - q2) * ca * cg + 2 * cc / bb * caca * cb);
  c[2] = 2 *
         (q1 * q1 - 1 + 2 * q1 * q1 * cbcb + 2 * q3 * caca - 4 * q2 * ca * cb * cg + 2 * q4 * cgcg);
  c[1] = 4 * (-q1 * (1 + q1) * cb + 2 * aa / bb * cgcg * cb - (1 - q2) * ca * cg);
  c[0] = (1 + q1) * (1 + q1) - 4 * aa / bb * cgcg;
  if (std::abs(c[4]) < 1e-12 * (std::abs(c[3]) + std::abs(c[2]) + std::abs(c[0]))) return 0;
  std::array<double, 4> roots{};
  const int n = real_quartic_roots(c, roots);
  int found = 0;
  for (int i = 0; i < n; ++i) {
    const double v = roots[static_cast<std::size_t>(i)];
    if (!(v > 0)) continue;
    const double denominator = 2 * (cg - v * ca);
    if (std::abs(denominator) < 1e-12) continue;
    const double u = ((q1 - 1) * v * v - 2 * q1 * cb * v + 1 + q1) / denominator;
    if (!(u > 0)) continue;
    const double ss = 1 + v * v - 2 * v * cb;
    if (!(ss > 0)) continue;
    const double s1 = std::sqrt(bb / ss);
    const std::array<Eigen::Vector3d, 3> seen = {s1 * j[0], u * s1 * j[1], v * s1 * j[2]};
    poses[static_cast<std::size_t>(found++)] = align_points(p.data(), seen.data(), 3);
  }
  return found;
}

}  // namespace epipole::calib
