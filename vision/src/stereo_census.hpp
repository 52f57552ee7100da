#pragma once

// The 9x7 centre-symmetric census of the stereo matcher: the 31 offsets (dx, dy) of the upper
// half window; bit b compares I(x + dx, y + dy) with I(x - dx, y - dy).
namespace epipole::vision::kernels {

constexpr int kCensusBits = 31;
// Block matching's census: the first 16 offsets alone, a checkerboard of the half window. A
// box sums 49 and more pixels' costs, which makes up for the sparser pattern (Aloe 640x480:
// bad2 23.0 % -> 23.3 %), and the cost row reads and counts half the bytes.
constexpr int kSparseCensusBits = 16;
constexpr int kCensusRadiusX = 4;
constexpr int kCensusRadiusY = 3;

struct CensusOffset {
  int dx;
  int dy;
};

// The checkerboard of the sparse census first (dx + dy odd: every other offset of each row of
// the window), then the other 15.
constexpr CensusOffset kCensusOffsets[kCensusBits] = {
    {-4, -3}, {-2, -3}, {0, -3},  {2, -3}, {4, -3},  {-3, -2}, {-1, -2}, {1, -2},
    {3, -2},  {-4, -1}, {-2, -1}, {0, -1}, {2, -1},  {4, -1},  {-3, 0},  {-1, 0},
    {-3, -3}, {-1, -3}, {1, -3},  {3, -3}, {-4, -2}, {-2, -2}, {0, -2},  {2, -2},
    {4, -2},  {-3, -1}, {-1, -1}, {1, -1}, {3, -1},  {-4, 0},  {-2, 0}};

// The table is the upper half window once, offset by offset, the checkerboard first.
constexpr bool census_table_is_whole() {
  bool seen[2 * kCensusRadiusY + 1][2 * kCensusRadiusX + 1] = {};
  for (int b = 0; b < kCensusBits; ++b) {
    const CensusOffset o = kCensusOffsets[b];
    const bool upper = o.dy < 0 || (o.dy == 0 && o.dx < 0);
    const bool checkerboard = (o.dx + o.dy) % 2 != 0;
    if (!upper || seen[o.dy + kCensusRadiusY][o.dx + kCensusRadiusX] ||
        checkerboard != (b < kSparseCensusBits)) {
      return false;
    }
    seen[o.dy + kCensusRadiusY][o.dx + kCensusRadiusX] = true;
  }
  return true;
}
static_assert(census_table_is_whole());

}  // namespace epipole::vision::kernels
