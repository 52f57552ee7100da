#pragma once

#include <filesystem>
#include <string_view>

namespace epipole::test {

// The path of a file of the fetched data sets (scripts/fetch-data.sh), e.g.
// data_file("samples/left01.jpg"). The folder is $EPIPOLE_DATA_DIR, else the one configured at
// build time. A missing file fails the calling test with a message saying how to fetch it.
std::filesystem::path data_file(std::string_view relative);

}  // namespace epipole::test
