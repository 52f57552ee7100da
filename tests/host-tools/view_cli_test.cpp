// epipole view: where a board's live view is, and whether it answers, against the firmware on
// the simulated board serving its view on the loopback interface.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "epipole/firmware/firmware.hpp"
#include "loopback.hpp"
#include "run_tool.hpp"
#include "sim_rig.hpp"
#include "test_paths.hpp"

namespace epipole::firmware {
namespace {

// The firmware with its view on a free port, run in a thread of its own.
struct ViewServed {
  test::SimRig rig{96, 64, 6};
  int port = test::free_port();
  std::unique_ptr<Firmware> fw;
  std::atomic<bool> stop{false};
  std::thread loop;
  ViewServed() {
    fw = std::make_unique<Firmware>(
        rig.replaying(rig.parse("outputs: {view: {port: " + std::to_string(port) + "}}\n"), 2));
    loop = std::thread([this] { fw->run(0, stop); });
  }
  ~ViewServed() {
    stop = true;
    loop.join();
  }
};

// epipole view on a desk: the addresses, and whether the board answers.
TEST(ViewCli, EpipoleViewSaysWhereTheViewIsAndWhetherItAnswers) {
  ViewServed served;
  for (int i = 0; i < 400 && test::http_request(served.port, "GET", "/api/health").status != 200;
       ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  const std::string where = "127.0.0.1:" + std::to_string(served.port);
  const test::ToolResult view = test::run_tool("view " + where);
  EXPECT_EQ(view.exit_code, 0) << view.out;
  EXPECT_NE(view.out.find("the page: http://" + where + "/"), std::string::npos) << view.out;
  EXPECT_NE(view.out.find("ws://" + where), std::string::npos) << view.out;
  EXPECT_NE(view.out.find("it answers: "), std::string::npos) << view.out;
  // Its board file: the same view.
  std::ofstream(served.rig.dir.path() / "board.yaml")
      << served.rig.yaml("outputs: {view: {port: " + std::to_string(served.port) + "}}\n");
  const test::ToolResult board = test::run_tool("view " + served.rig.dir.path().string());
  EXPECT_EQ(board.exit_code, 0) << board.out;
  EXPECT_NE(board.out.find("it answers: "), std::string::npos) << board.out;

  const int nobody = test::free_port();
  const test::ToolResult none = test::run_tool("view 127.0.0.1:" + std::to_string(nobody));
  EXPECT_EQ(none.exit_code, 1);
  EXPECT_NE(none.out.find("nothing answers at 127.0.0.1:" + std::to_string(nobody)),
            std::string::npos)
      << none.out;
  const test::ToolResult no_view =
      test::run_tool("view " + (std::filesystem::path(test::source_dir()) / "board/sim").string());
  EXPECT_EQ(no_view.exit_code, 1);
  EXPECT_NE(no_view.out.find("the board has no live view"), std::string::npos) << no_view.out;
  EXPECT_NE(test::run_tool("view 127.0.0.1:notaport").out.find("'notaport' is not a port"),
            std::string::npos);
}

}  // namespace
}  // namespace epipole::firmware
