// A stage's own section of the board file: the stage's reader gets it (or nothing, for its
// defaults), a bad value is its reader's error naming the file and the key, and the stage finds
// what it read, or its defaults in a configuration made without a file.
#include "config/stage_sections.hpp"

#include <gtest/gtest.h>

#include <array>
#include <memory>
#include <optional>

#include "epipole/core/thread_pool.hpp"
#include "epipole/core/yaml_fields.hpp"
#include "error_of.hpp"

namespace epipole::firmware::stages {
namespace {

using test::error_of;

// What a stage with settings of its own would write in its file.
struct ClearanceSettings final : StageSettings {
  int clearance_mm = 100;
  std::unique_ptr<StageSettings> clone() const override {
    return std::make_unique<ClearanceSettings>(*this);
  }
};

std::unique_ptr<StageSettings> read_clearance(const YAML::Node& section, const yaml::Fields& f) {
  auto s = std::make_unique<ClearanceSettings>();
  if (section.IsDefined()) {
    f.only_keys(section, "rectify", {"clearance_mm"});
    f.if_present(section, "rectify", "clearance_mm",
                 [&](const YAML::Node& n, const std::string& k) {
                   s->clearance_mm = f.integer_in(n, k, 0, 2000);
                 });
  }
  return s;
}

const StageDefinition with_settings{nullptr, read_clearance};
const StageDefinition without_settings{nullptr, nullptr};
const std::array<StageRow, 2> kRows{
    {{protocol::Stage::corners, &without_settings}, {protocol::Stage::rectify, &with_settings}}};

StageSections read(const std::string& yaml) {
  const yaml::Fields f("board.yaml");
  StageSections sections;
  read_stage_sections(kRows, f.parse(yaml), f, sections);
  return sections;
}

int clearance_of(const BoardConfig& board) {
  ThreadPool pool(1);
  const std::optional<calib::StereoCalibration> none;
  const StageContext context{board,   none,   SimdPath::reference, nullptr, pool, nullptr, nullptr,
                             nullptr, nullptr};
  return settings_of<ClearanceSettings>(context, protocol::Stage::rectify).clearance_mm;
}

TEST(StageSections, AStageReadsItsOwnSectionAndOnlyAStageWithAReaderHasOne) {
  BoardConfig board;
  board.stage_sections = read("rectify: {clearance_mm: 250}\ncorners: {threshold: 30}\n");
  EXPECT_EQ(clearance_of(board), 250);
  EXPECT_EQ(board.stage_sections.find("corners"), nullptr) << "the board reader's own section";
}

TEST(StageSections, WithoutItsSectionAStageHasItsDefaults) {
  BoardConfig board;
  board.stage_sections = read("name: test\n");
  ASSERT_NE(board.stage_sections.find("rectify"), nullptr) << "read with nothing: its defaults";
  EXPECT_EQ(clearance_of(board), 100);
  EXPECT_EQ(clearance_of(BoardConfig{}), 100) << "a configuration made without a file";
}

TEST(StageSections, ABadValueIsTheStagesErrorNamingTheFileAndTheKey) {
  EXPECT_EQ(error_of([] { read("rectify: {clearance_mm: 9000}\n"); }),
            "board.yaml: rectify.clearance_mm: 9000 is outside 0..2000");
  EXPECT_NE(error_of([] { read("rectify: {height: 1}\n"); }).find("height"), std::string::npos);
}

struct OtherSettings final : StageSettings {
  std::unique_ptr<StageSettings> clone() const override {
    return std::make_unique<OtherSettings>(*this);
  }
};

TEST(StageSections, SettingsOfAnotherTypeAreAnErrorNotTheDefaults) {
  BoardConfig board;
  board.stage_sections.set("rectify", std::make_unique<OtherSettings>());
  EXPECT_NE(error_of([&] { clearance_of(board); }).find("stage rectify"), std::string::npos);
}

TEST(StageSections, ACopiedBoardConfigurationCopiesTheStagesSettings) {
  BoardConfig board;
  board.stage_sections = read("rectify: {clearance_mm: 40}\n");
  BoardConfig copy = board;
  board.stage_sections = read("rectify: {clearance_mm: 60}\n");
  EXPECT_EQ(clearance_of(copy), 40);
  EXPECT_EQ(clearance_of(board), 60);
}

}  // namespace
}  // namespace epipole::firmware::stages
