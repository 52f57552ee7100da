#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/hal/device_missing.hpp"
#include "epipole/hal/registry.hpp"
#include "error_of.hpp"
#include "libcamera/libcamera_camera.hpp"

namespace epipole::hal {
namespace {

using test::error_of;

constexpr Nanoseconds kMs = 1'000'000;

LibcameraFormatCode code_of(const char* name) {
  for (const LibcameraFormat& f : libcamera_formats()) {
    if (std::string(f.name) == name) return {f.fourcc, f.modifier};
  }
  ADD_FAILURE() << name << " is not in the table";
  return {};
}

TEST(LibcameraFormats, TableMapsOurFormats) {
  EXPECT_EQ(libcamera_formats().size(), 9u);
  const LibcameraFormatCode r8 = code_of("R8");
  EXPECT_EQ(r8.fourcc, 0x20203852u) << "'R8  ' as libcamera (DRM) writes it";
  EXPECT_EQ(r8.modifier, 0u);
  const LibcameraFormatCode r10 = code_of("R10");
  const LibcameraFormatCode packed = code_of("R10_CSI2P");
  EXPECT_EQ(r10.fourcc, packed.fourcc) << "the packing is in the modifier";
  EXPECT_EQ(packed.modifier, (std::uint64_t{11} << 56) | 1);
  EXPECT_EQ(find_libcamera_format(packed)->layout, LibcameraLayout::r10_csi2p);
  EXPECT_EQ(find_libcamera_format(r10)->layout, LibcameraLayout::r10);
  EXPECT_EQ(find_libcamera_format({0x47504a4du, 0}), nullptr) << "MJPG";
  for (const auto& [name, format] :
       std::vector<std::pair<const char*, PixelFormat>>{{"R8", PixelFormat::grey},
                                                        {"R10", PixelFormat::y10},
                                                        {"R16", PixelFormat::y16},
                                                        {"YUYV", PixelFormat::yuyv},
                                                        {"NV12", PixelFormat::nv12},
                                                        {"YUV420", PixelFormat::yu12}}) {
    const LibcameraFormat* f = find_libcamera_format(code_of(name));
    ASSERT_NE(f, nullptr) << name;
    EXPECT_TRUE(f->requestable) << name;
    EXPECT_EQ(f->format, format) << name;
  }
  EXPECT_FALSE(find_libcamera_format(code_of("BGR888"))->requestable);
  EXPECT_TRUE(is_zero_copy(LibcameraLayout::yuv420));
  EXPECT_FALSE(is_zero_copy(LibcameraLayout::r10_csi2p));
  EXPECT_EQ(row_bytes(LibcameraLayout::r10_csi2p, 6), 10u);
  EXPECT_EQ(row_bytes(LibcameraLayout::r10_csi2p, 8), 10u);
  EXPECT_EQ(row_bytes(LibcameraLayout::rgb888, 5), 15u);
}

TEST(LibcameraFormats, ChoiceTakesTheRequestedThenZeroCopy) {
  auto choose = [](PixelFormat requested, std::vector<const char*> names) {
    std::vector<LibcameraFormatCode> codes;
    for (const char* n : names) codes.push_back(code_of(n));
    codes.push_back({0x47504a4du, 0});  // MJPG: never taken
    const LibcameraFormat* f = choose_libcamera_format(requested, codes);
    return std::string(f != nullptr ? f->name : "none");
  };
  // A mono sensor's raw stream (OV9281 on a Raspberry Pi).
  EXPECT_EQ(choose(PixelFormat::y10, {"R8", "R10_CSI2P"}), "R10_CSI2P");
  EXPECT_EQ(choose(PixelFormat::grey, {"R10_CSI2P", "R8"}), "R8");
  EXPECT_EQ(choose(PixelFormat::y10, {"R10_CSI2P", "R10"}), "R10") << "unpacked first";
  EXPECT_EQ(choose(PixelFormat::y16, {"R10_CSI2P"}), "R10_CSI2P");
  // An ISP's output: zero-copy before conversions.
  EXPECT_EQ(choose(PixelFormat::grey, {"YUYV", "YUV420", "NV12"}), "NV12");
  EXPECT_EQ(choose(PixelFormat::yuyv, {"NV12", "YUYV"}), "YUYV");
  // vimc offers RGB only: taken when nothing else is.
  EXPECT_EQ(choose(PixelFormat::grey, {"BGR888", "RGB888"}), "RGB888");
  EXPECT_EQ(choose(PixelFormat::grey, {}), "none");
}

TEST(LibcameraConvert, ZeroCopyLayoutsViewThePlane) {
  std::vector<std::uint8_t> plane(8 * 4 * 3 / 2);
  for (std::size_t i = 0; i < plane.size(); ++i) plane[i] = static_cast<std::uint8_t>(i);
  for (const LibcameraLayout l :
       {LibcameraLayout::r8, LibcameraLayout::nv12, LibcameraLayout::yuv420}) {
    const GrayView v = gray_view(l, plane.data(), plane.size(), 6, 4, 8, {});
    EXPECT_EQ(v.data(), plane.data());
    EXPECT_EQ(v.stride(), 8);
    EXPECT_EQ(v(5, 3), 3 * 8 + 5);
  }
}

TEST(LibcameraConvert, PackedTenBitRgbAndTheV4l2Layouts) {
  // R10_CSI2P, width 6: pixels 0..3 in bytes 0..3 (high bits) + byte 4 (low bits), pixels 4, 5
  // in bytes 5, 6 + bytes 7, 8 (unused) and the low-bit byte 9; stride 12.
  const std::vector<std::uint8_t> packed = {10, 20, 30, 40, 0xff, 50, 60, 0, 0, 0xff, 0, 0,
                                            11, 21, 31, 41, 0x00, 51, 61, 0, 0, 0x00, 0, 0};
  GrayImage scratch(6, 2);
  GrayView v =
      gray_view(LibcameraLayout::r10_csi2p, packed.data(), packed.size(), 6, 2, 12, scratch.view());
  EXPECT_EQ(v.data(), scratch.view().data());
  const std::array<int, 6> row0 = {10, 20, 30, 40, 50, 60};
  for (int x = 0; x < 6; ++x) {
    EXPECT_EQ(v(x, 0), row0[static_cast<std::size_t>(x)]) << x;
    EXPECT_EQ(v(x, 1), row0[static_cast<std::size_t>(x)] + 1) << x;
  }
  // RGB888 is B, G, R in memory; BGR888 R, G, B. Red, green, blue, white, black.
  const std::vector<std::uint8_t> rgb = {0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 0, 0, 0};
  GrayImage luma(5, 1);
  v = gray_view(LibcameraLayout::rgb888, rgb.data(), rgb.size(), 5, 1, 15, luma.view());
  EXPECT_EQ(v(0, 0), 77);
  EXPECT_EQ(v(1, 0), 149);
  EXPECT_EQ(v(2, 0), 29);
  EXPECT_EQ(v(3, 0), 255);
  EXPECT_EQ(v(4, 0), 0);
  v = gray_view(LibcameraLayout::bgr888, rgb.data(), rgb.size(), 5, 1, 15, luma.view());
  EXPECT_EQ(v(0, 0), 29) << "the same bytes read as R, G, B: blue";
  EXPECT_EQ(v(2, 0), 77);
  // R10 (10 bits in 16), R16 and YUYV go through the V4L2 backend's conversions.
  const std::vector<std::uint8_t> words = {0xff, 0x03, 0x34, 0x12};
  GrayImage two(2, 1);
  EXPECT_EQ(gray_view(LibcameraLayout::r10, words.data(), 4, 2, 1, 4, two.view())(0, 0), 255);
  EXPECT_EQ(gray_view(LibcameraLayout::r16, words.data(), 4, 2, 1, 4, two.view())(1, 0), 0x12);
  EXPECT_EQ(gray_view(LibcameraLayout::yuyv, words.data(), 4, 2, 1, 4, two.view())(1, 0), 0x34);
  // Truncated planes, short strides and wrong conversion buffers are errors.
  EXPECT_THROW(gray_view(LibcameraLayout::r10_csi2p, packed.data(), 20, 6, 2, 12, scratch.view()),
               Error);
  EXPECT_THROW(
      gray_view(LibcameraLayout::r10_csi2p, packed.data(), packed.size(), 6, 2, 9, scratch.view()),
      Error);
  EXPECT_THROW(gray_view(LibcameraLayout::rgb888, rgb.data(), rgb.size(), 5, 1, 15, two.view()),
               Error);
}

TEST(LibcameraCameras, ChosenByIdOrIndexAndErrorsListThem) {
  const std::vector<std::string> ids = {"/base/soc/i2c0mux/i2c@0/ov9281@60",
                                        "/base/soc/i2c0mux/i2c@1/ov9281@60"};
  EXPECT_EQ(select_camera("/base/soc/i2c0mux/i2c@1/ov9281@60", ids), 1u);
  EXPECT_EQ(select_camera("0", ids), 0u);
  EXPECT_EQ(select_camera("1", ids), 1u);
  EXPECT_EQ(error_of([&] { select_camera("2", ids); }),
            "camera 2: no libcamera camera with that index (cameras found: 0: "
            "/base/soc/i2c0mux/i2c@0/ov9281@60, 1: /base/soc/i2c0mux/i2c@1/ov9281@60)");
  EXPECT_EQ(error_of([&] { select_camera("ov9281", {}); }),
            "camera ov9281: no libcamera camera with that id (cameras found: none)");
}

RequestCompletion done(int slot, std::uint32_t generation, std::uint32_t sequence) {
  RequestCompletion c;
  c.slot = slot;
  c.generation = generation;
  c.sequence = sequence;
  c.timestamp = 1000 + sequence;
  return c;
}

TEST(RequestRing, CompletionsInTheOrderTheyCame) {
  RequestRing ring;
  const std::uint32_t g = ring.start(4);
  EXPECT_EQ(ring.queued(), 4);
  RequestCompletion c;
  EXPECT_EQ(ring.wait(0, c), RequestRing::Wait::timeout);
  EXPECT_EQ(ring.wait(kMs, c), RequestRing::Wait::timeout);
  // Out of order: slot 2 before slot 0.
  EXPECT_TRUE(ring.complete(done(2, g, 7)));
  EXPECT_TRUE(ring.complete(done(0, g, 8)));
  EXPECT_FALSE(ring.complete(done(2, g, 9))) << "slot 2 is not queued";
  EXPECT_FALSE(ring.complete(done(1, g + 1, 9))) << "another generation";
  EXPECT_FALSE(ring.complete(done(4, g, 9))) << "no such slot";
  EXPECT_EQ(ring.ready(), 2);
  ASSERT_EQ(ring.wait(kMs, c), RequestRing::Wait::ok);
  EXPECT_EQ(c.slot, 2);
  EXPECT_EQ(c.sequence, 7u);
  ASSERT_EQ(ring.wait(kMs, c), RequestRing::Wait::ok);
  EXPECT_EQ(c.slot, 0);
  EXPECT_EQ(ring.lent(), 2);
  EXPECT_TRUE(ring.give_back(2, g));
  EXPECT_FALSE(ring.give_back(2, g)) << "given back twice";
  EXPECT_FALSE(ring.give_back(1, g)) << "never lent";
  EXPECT_TRUE(ring.complete(done(2, g, 10))) << "queued again";
  EXPECT_EQ(ring.queued(), 2);
}

TEST(RequestRing, AnOldGenerationAfterARestartIsIgnored) {
  RequestRing ring;
  const std::uint32_t g1 = ring.start(3);
  ASSERT_TRUE(ring.complete(done(1, g1, 1)));
  RequestCompletion c;
  ASSERT_EQ(ring.wait(0, c), RequestRing::Wait::ok);
  ring.stop();  // a reopen: the frame of slot 1 is still held by the caller
  EXPECT_EQ(ring.wait(0, c), RequestRing::Wait::lost) << "not streaming";
  const std::uint32_t g2 = ring.start(3);
  EXPECT_NE(g1, g2);
  EXPECT_FALSE(ring.give_back(1, g1));
  EXPECT_EQ(ring.queued(), 3) << "the old frame changed nothing";
  EXPECT_FALSE(ring.complete(done(0, g1, 2))) << "a late completion of the old stream";
  EXPECT_TRUE(ring.complete(done(1, g2, 2)));
}

TEST(RequestRing, AnotherThreadWakesTheWaiter) {
  RequestRing ring;
  const std::uint32_t g = ring.start(2);
  std::thread completer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    ring.complete(done(1, g, 3));
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    ring.lose();
  });
  RequestCompletion c;
  EXPECT_EQ(ring.wait(10'000 * kMs, c), RequestRing::Wait::ok);
  EXPECT_EQ(c.slot, 1);
  EXPECT_EQ(ring.wait(10'000 * kMs, c), RequestRing::Wait::lost);
  completer.join();
  EXPECT_EQ(ring.wait(0, c), RequestRing::Wait::lost) << "until the next start";
  ring.start(2);
  EXPECT_EQ(ring.wait(0, c), RequestRing::Wait::timeout);
}

// What the camera would do with a request the stream gives back: here, remember it.
class FakeRequeuer final : public LibcameraStream::Requeuer {
 public:
  bool requeue(int slot) override {
    requeued.push_back(slot);
    return accept;
  }
  std::vector<int> requeued;
  bool accept = true;
};

struct FakeBuffers {
  FakeBuffers(int count, std::size_t bytes) : storage(static_cast<std::size_t>(count)) {
    for (std::size_t i = 0; i < storage.size(); ++i) {
      storage[i].assign(bytes, static_cast<std::uint8_t>(10 * i));
      planes.push_back({storage[i].data(), bytes});
    }
  }
  std::vector<std::vector<std::uint8_t>> storage;
  std::vector<MappedPlane> planes;
};

const LibcameraFormat& format_named(const char* name) {
  return *find_libcamera_format(code_of(name));
}

// A stream of `count` fake buffers of `bytes` each, started for a format and geometry.
struct FakeStream {
  FakeStream(int count, std::size_t bytes) : buffers(count, bytes) {}
  std::uint32_t start(const char* format, int width, int height, std::size_t stride) {
    return stream.start("cam0", format_named(format), width, height, stride, buffers.planes,
                        requeuer);
  }
  FakeBuffers buffers;
  FakeRequeuer requeuer;
  LibcameraStream stream;
};

TEST(LibcameraStream, FramesViewTheMappedPlanes) {
  FakeStream fake(3, 16 * 8);
  EXPECT_EQ(fake.stream.acquire(0).status, AcquireStatus::device_lost) << "not started";
  const std::uint32_t g = fake.start("R8", 16, 8, 16);
  EXPECT_EQ(fake.stream.acquire(kMs).status, AcquireStatus::timeout);
  ASSERT_TRUE(fake.stream.ring().complete(done(1, g, 41)));
  const AcquireResult r = fake.stream.acquire(kMs);
  ASSERT_EQ(r.status, AcquireStatus::ok);
  EXPECT_EQ(r.frame.gray.data(), fake.buffers.storage[1].data()) << "zero copy";
  EXPECT_EQ(r.frame.gray(3, 2), 10);
  EXPECT_EQ(r.frame.sequence, 41u);
  EXPECT_EQ(r.frame.timestamp, 1041);
  EXPECT_EQ(r.frame.clock, ClockId::monotonic);
  EXPECT_EQ(r.frame.buffer, 1);
  EXPECT_TRUE(fake.requeuer.requeued.empty());
  fake.stream.release(r.frame);
  fake.stream.release(r.frame);
  EXPECT_EQ(fake.requeuer.requeued, std::vector<int>{1}) << "requeued once";
}

TEST(LibcameraStream, CancelledDamagedAndShortRequestsGoBack) {
  FakeStream fake(4, 16 * 8);
  const std::uint32_t g = fake.start("R8", 16, 8, 16);
  RequestCompletion cancelled = done(0, g, 1);
  cancelled.cancelled = true;
  RequestCompletion damaged = done(1, g, 2);
  damaged.damaged = true;
  RequestCompletion short_one = done(2, g, 3);
  short_one.bytes_used = 16 * 7;
  ASSERT_TRUE(fake.stream.ring().complete(cancelled));
  ASSERT_TRUE(fake.stream.ring().complete(damaged));
  ASSERT_TRUE(fake.stream.ring().complete(short_one));
  ASSERT_TRUE(fake.stream.ring().complete(done(3, g, 4)));
  EXPECT_EQ(fake.stream.acquire(kMs).status, AcquireStatus::corrupt)
      << "cancelled skipped, damaged";
  EXPECT_EQ(fake.stream.acquire(kMs).status, AcquireStatus::corrupt) << "short";
  const AcquireResult r = fake.stream.acquire(kMs);
  ASSERT_EQ(r.status, AcquireStatus::ok);
  EXPECT_EQ(r.frame.sequence, 4u);
  EXPECT_EQ(fake.requeuer.requeued, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(fake.stream.ring().queued(), 3);
}

TEST(LibcameraStream, ConversionsUseOneBufferPerRequest) {
  FakeStream fake(2, 10 * 4);
  const std::uint32_t g = fake.start("R10_CSI2P", 8, 4, 10);
  ASSERT_TRUE(fake.stream.ring().complete(done(0, g, 1)));
  ASSERT_TRUE(fake.stream.ring().complete(done(1, g, 2)));
  const AcquireResult a = fake.stream.acquire(kMs);
  const AcquireResult b = fake.stream.acquire(kMs);
  ASSERT_EQ(a.status, AcquireStatus::ok);
  ASSERT_EQ(b.status, AcquireStatus::ok);
  EXPECT_NE(a.frame.gray.data(), b.frame.gray.data());
  EXPECT_EQ(a.frame.gray(7, 3), 0);
  EXPECT_EQ(b.frame.gray(7, 3), 10);
}

TEST(LibcameraStream, ReleaseAfterARestartAndRefusedRequeues) {
  FakeStream fake(2, 16 * 8);
  std::uint32_t g = fake.start("R8", 16, 8, 16);
  ASSERT_TRUE(fake.stream.ring().complete(done(0, g, 1)));
  const AcquireResult old = fake.stream.acquire(kMs);
  ASSERT_EQ(old.status, AcquireStatus::ok);
  g = fake.start("R8", 16, 8, 16);  // reopen
  fake.stream.release(old.frame);
  EXPECT_TRUE(fake.requeuer.requeued.empty()) << "a frame of the old stream is not requeued";
  EXPECT_EQ(fake.stream.ring().queued(), 2);
  // The camera refuses a request (it is gone): the stream reports device_lost.
  fake.requeuer.accept = false;
  ASSERT_TRUE(fake.stream.ring().complete(done(1, g, 2)));
  const AcquireResult r = fake.stream.acquire(kMs);
  ASSERT_EQ(r.status, AcquireStatus::ok);
  fake.stream.release(r.frame);
  EXPECT_EQ(fake.stream.acquire(kMs).status, AcquireStatus::device_lost);
  fake.stream.stop();
  EXPECT_EQ(fake.stream.acquire(kMs).status, AcquireStatus::device_lost);
}

TEST(LibcameraStream, PlanesTooSmallNameTheDevice) {
  FakeStream fake(2, 100);
  EXPECT_EQ(error_of([&] { fake.start("YUYV", 16, 8, 32); }),
            "camera cam0: frame buffer 0 holds 100 bytes, YUYV 16x8 needs 256");
  EXPECT_EQ(error_of([&] { fake.start("YUYV", 16, 8, 16); }),
            "camera cam0: stride 16 is below the 32 bytes of a 16-pixel YUYV row");
}

// An OV9281 as the Raspberry Pi pipeline states it: exposure 29..66666 us, analogue gain 1..16.
LibcameraExposureLimits ov9281(bool modes) {
  LibcameraExposureLimits l;
  l.exposure_time = {true, true, 29, 66666};
  l.analogue_gain = {true, true, 1.0, 16.0};
  l.ae_enable = !modes;
  l.exposure_time_mode = modes;
  l.analogue_gain_mode = modes;
  return l;
}

LibcameraExposureControls plan(Nanoseconds exposure, double gain,
                               const LibcameraExposureLimits& limits, bool modes,
                               bool starting = false) {
  return plan_libcamera_exposure("cam0", "/base/ov9281@60", exposure, gain, limits, modes,
                                 starting);
}

TEST(LibcameraControls, ManualAndAutomaticBeforeAndAfterTheModeControls) {
  // Before libcamera 0.5: the values, and AeEnable off when both are manual, on otherwise.
  LibcameraExposureControls c = plan(4'000'000, 2.0, ov9281(false), false);
  EXPECT_EQ(c.exposure_time_us, 4000);
  EXPECT_EQ(c.analogue_gain, 2.0f);
  EXPECT_EQ(c.ae_enable, false);
  EXPECT_FALSE(c.exposure_time_manual.has_value());
  c = plan(0, 2.0, ov9281(false), false);
  EXPECT_FALSE(c.exposure_time_us.has_value());
  EXPECT_EQ(c.analogue_gain, 2.0f);
  EXPECT_EQ(c.ae_enable, true) << "the exposure stays automatic, the gain fixed";
  c = plan(0, 0.0, ov9281(false), false);
  EXPECT_EQ(c.ae_enable, true);
  EXPECT_FALSE(c.analogue_gain.has_value());
  // 0.5 on: each value's own mode.
  c = plan(4'000'000, 0.0, ov9281(true), true);
  EXPECT_EQ(c.exposure_time_us, 4000);
  EXPECT_EQ(c.exposure_time_manual, true);
  EXPECT_EQ(c.analogue_gain_manual, false);
  EXPECT_FALSE(c.ae_enable.has_value());
  // 500 ns is less than a microsecond: at least 1 us is asked (here below the camera's 29).
  LibcameraExposureLimits open = ov9281(false);
  open.exposure_time.bounded = false;
  EXPECT_EQ(plan(500, 0.0, open, false).exposure_time_us, 1);
  // A camera without the controls that turn automatic on: left as it is at start-up only.
  LibcameraExposureLimits bare = ov9281(false);
  bare.ae_enable = false;
  c = plan(0, 0.0, bare, false, true);
  EXPECT_FALSE(c.ae_enable.has_value());
  EXPECT_FALSE(c.exposure_time_us.has_value());
}

TEST(LibcameraControls, MissingControlsAndValuesOutOfRangeAreNamed) {
  const auto message = [](Nanoseconds exposure, double gain, const LibcameraExposureLimits& l,
                          bool modes) { return error_of([&] { plan(exposure, gain, l, modes); }); };
  EXPECT_EQ(message(100'000'000, 2.0, ov9281(false), false),
            "camera cam0: exposure 100000000 ns is outside the camera's 29..66666 us");
  EXPECT_EQ(message(4'000'000, 20.0, ov9281(false), false),
            "camera cam0: gain 20 is outside the camera's analogue gain 1..16");
  LibcameraExposureLimits bare;
  EXPECT_EQ(message(4'000'000, 0.0, bare, false),
            "camera cam0: exposure 4000000 ns: libcamera camera /base/ov9281@60 has no "
            "ExposureTime control");
  EXPECT_EQ(message(0, 2.0, bare, false),
            "camera cam0: gain 2: libcamera camera /base/ov9281@60 has no AnalogueGain control");
  EXPECT_EQ(message(0, 0.0, bare, false),
            "camera cam0: automatic exposure: libcamera camera /base/ov9281@60 has no AeEnable "
            "control");
  LibcameraExposureLimits no_modes = ov9281(true);
  no_modes.analogue_gain_mode = false;
  EXPECT_EQ(message(4'000'000, 0.0, no_modes, true),
            "camera cam0: automatic gain: libcamera camera /base/ov9281@60 has no "
            "AnalogueGainMode control");
}

// A camera libcamera does not list is made all the same (it is waited for: a USB camera at
// boot); starting it says it is missing and lists what libcamera found.
TEST(LibcameraBackend, RegisteredAndMissingCamerasNamed) {
  CameraConfig config;
  config.device = "cam-epipole-missing";
  const auto start_error = [](const CameraConfig& c) {
    return error_of([&] { BackendRegistry::builtin().create_camera("libcamera", c)->start(); });
  };
  const std::string m = start_error(config);
  if (libcamera_build_version().empty()) {
    EXPECT_NE(m.find("backend 'libcamera' is not built into this binary: "), std::string::npos)
        << m;
    EXPECT_FALSE(EPIPOLE_HAVE_LIBCAMERA) << "CMake found libcamera, the binary has not";
    return;
  }
  EXPECT_TRUE(EPIPOLE_HAVE_LIBCAMERA);
  EXPECT_EQ(libcamera_build_version(), EPIPOLE_LIBCAMERA_VERSION);
  EXPECT_NE(m.find("camera cam-epipole-missing: no libcamera camera with that id (cameras found: "),
            std::string::npos)
      << m;
  try {
    BackendRegistry::builtin().create_camera("libcamera", config)->start();
    ADD_FAILURE() << "a missing camera cannot start";
  } catch (const DeviceMissing&) {
  }
  config.device = "7";
  const std::string by_index = start_error(config);
  EXPECT_NE(by_index.find("camera 7: no libcamera camera with that index"), std::string::npos)
      << by_index;
  config.width = 0;
  EXPECT_NE(error_of([&] {
              BackendRegistry::builtin().create_camera("libcamera", config);
            }).find("camera 7: size 0x480 is impossible"),
            std::string::npos)
      << "the configuration is checked before libcamera is asked";
}

}  // namespace
}  // namespace epipole::hal
