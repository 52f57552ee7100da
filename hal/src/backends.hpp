#pragma once

// Each backend's folder (hal/src/<backend>/) defines, in namespace epipole::hal,
//   void register_<backend>(BackendRegistry& registry);
// which adds its devices (and its board-file section, if it has one) to the registry; a backend
// that is known but not built registers the reason instead (the *_unavailable.cpp of its
// folder). hal/CMakeLists.txt's list of backends generates the call of each, in its order.
namespace epipole::hal {

class BackendRegistry;

// Every backend of hal/CMakeLists.txt's list (the generated builtin_backends.cpp).
void register_builtin_backends(BackendRegistry& registry);

}  // namespace epipole::hal
