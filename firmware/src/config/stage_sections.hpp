#pragma once

// The board file's stage sections: each stage with settings of its own
// (StageDefinition::read_settings) reads the top-level section of its name.

#include <span>

#include "epipole/firmware/board_config.hpp"
#include "stages/stage.hpp"

namespace epipole::firmware::stages {

// Hands each section to its stage's reader (an undefined node when the file has none: the
// stage's defaults) and keeps what it read in `out`; a bad value is the reader's Error.
void read_stage_sections(std::span<const StageRow> rows, const YAML::Node& root,
                         const yaml::Fields& fields, StageSections& out);

}  // namespace epipole::firmware::stages
