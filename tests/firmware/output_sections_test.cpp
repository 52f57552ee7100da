// The board file's `outputs`: a subsection turns an output on, read by the output itself; a
// name that is no output's, or a bad value, is an error naming the file and the key.
#include <gtest/gtest.h>

#include <fstream>

#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/firmware.hpp"
#include "error_of.hpp"
#include "sim_rig.hpp"

namespace epipole::firmware {
namespace {

using test::error_of;

TEST(OutputSections, AnOutputIsOnWhenTheFileHasItsSubsection) {
  const test::SimRig rig;
  EXPECT_EQ(rig.parse().outputs.find("mcap"), nullptr) << "off by default";
  const BoardConfig on = rig.parse("outputs: {mcap: {directory: recordings}}\n");
  EXPECT_NE(on.outputs.find("mcap"), nullptr);
  const BoardConfig copy = on;  // the settings are copied with the configuration
  EXPECT_NE(copy.outputs.find("mcap"), nullptr);
}

TEST(OutputSections, WhatIsNotAnOutputsIsAnErrorNamingTheKey) {
  const test::SimRig rig;
  EXPECT_EQ(error_of([&] { rig.parse("outputs: {mcpa: {directory: r}}\n"); }),
            (rig.dir.path() / "board.yaml").string() +
                ": outputs.mcpa: no output of that name (the outputs: mcap, ros2, view)");
  EXPECT_NE(error_of([&] { rig.parse("outputs: [mcap]\n"); }).find("outputs"), std::string::npos);
  EXPECT_NE(error_of([&] {
              rig.parse("outputs: {mcap: {directory: r, every: 0}}\n");
            }).find("outputs.mcap.every: 0 is outside 1..1000"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              rig.parse("outputs: {mcap: {directory: r, colour: red}}\n");
            }).find("unknown key 'outputs.mcap.colour'"),
            std::string::npos);
  EXPECT_NE(error_of([&] { rig.parse("outputs: {mcap: }\n"); }).find("outputs.mcap.directory"),
            std::string::npos)
      << "a recording needs a folder";
  EXPECT_NE(error_of([&] {
              rig.parse("outputs: {mcap: {directory: r, file_mb: 100, total_mb: 50}}\n");
            }).find("outputs.mcap.total_mb"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              rig.parse("outputs: {mcap: {directory: r, namespace: epipole}}\n");
            }).find("outputs.mcap.namespace"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              rig.parse("outputs: {view: {port: 70000}}\n");
            }).find("outputs.view.port: 70000 is outside 0..65535"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              rig.parse("outputs: {view: {clients: 0}}\n");
            }).find("outputs.view.clients: 0 is outside 1..16"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              rig.parse("outputs: {view: {bind: localhost}}\n");
            }).find("outputs.view.bind: 'localhost' is not an IPv4 address"),
            std::string::npos);
}

TEST(OutputSections, ARecordingFolderThatCannotBeMadeStopsTheStart) {
  const test::SimRig rig;
  std::ofstream(rig.dir.path() / "file") << "not a folder";
  const BoardConfig config = rig.parse("outputs: {mcap: {directory: file/recordings}}\n");
  const std::string error = error_of([&] { const Firmware fw(rig.replaying(config)); });
  EXPECT_NE(error.find("outputs.mcap.directory"), std::string::npos) << error;
  EXPECT_NE(error.find("cannot be made in"), std::string::npos) << error;
}

}  // namespace
}  // namespace epipole::firmware
