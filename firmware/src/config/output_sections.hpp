#pragma once

// The board file's `outputs` section: a subsection per output the file turns on, each read by
// its output (OutputDefinition::read_settings).

#include <span>

#include "epipole/firmware/board_config.hpp"
#include "outputs/output.hpp"

namespace epipole::firmware::outputs {

// Hands each subsection of `outputs` to its output's reader (`<name>:` alone: its defaults) and
// keeps what it read in `out`; a name no output has, or a bad value, is an Error.
void read_output_sections(std::span<const OutputFile> files, const YAML::Node& root,
                          const yaml::Fields& fields, OutputSections& out);

}  // namespace epipole::firmware::outputs
