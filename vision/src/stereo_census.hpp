#pragma once

// The 9x7 centre-symmetric census of the stereo matcher: the 31 offsets (dx, dy) of the upper
// half window; bit b compares I(x + dx, y + dy) with I(x - dx, y - dy).
namespace epipole::vision::kernels {

constexpr int kCensusBits = 31;
constexpr int kCensusRadiusX = 4;
constexpr int kCensusRadiusY = 3;
constexpr int kMaxCensusCost = 31;

struct CensusOffset {
  int dx;
  int dy;
};

constexpr CensusOffset kCensusOffsets[kCensusBits] = {
    {-4, -3}, {-3, -3}, {-2, -3}, {-1, -3}, {0, -3},  {1, -3},  {2, -3}, {3, -3},
    {4, -3},  {-4, -2}, {-3, -2}, {-2, -2}, {-1, -2}, {0, -2},  {1, -2}, {2, -2},
    {3, -2},  {4, -2},  {-4, -1}, {-3, -1}, {-2, -1}, {-1, -1}, {0, -1}, {1, -1},
    {2, -1},  {3, -1},  {4, -1},  {-4, 0},  {-3, 0},  {-2, 0},  {-1, 0}};

}  // namespace epipole::vision::kernels
