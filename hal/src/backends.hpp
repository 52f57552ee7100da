#pragma once

// Each backend's folder (hal/src/<backend>/) adds itself to the built-in registry through one
// of these; a backend that is known but not built registers the reason instead (the
// *_unavailable.cpp of its folder).
namespace epipole::hal {

class BackendRegistry;

void register_sim(BackendRegistry& registry);        // sim/sim_backend.cpp: cameras and trigger
void register_v4l2(BackendRegistry& registry);       // v4l2/v4l2_camera.cpp
void register_libcamera(BackendRegistry& registry);  // libcamera/libcamera_camera.cpp
void register_gpiod(BackendRegistry& registry);      // gpiod/gpiod_trigger.cpp
void register_termios(BackendRegistry& registry);    // termios/termios_serial.cpp
void register_pty(BackendRegistry& registry);        // pty/pty_serial.cpp

}  // namespace epipole::hal
