// Embree's device error callback, shared by the module's two Embree users (the scene of
// embree_scene.cpp and the box collider of box_overlaps.cpp).
#pragma once

#include <embree3/rtcore.h>

#include <string>

namespace cdp::embree {

// Keeps the first error an Embree device reports in the std::string `user` points to, so the
// caller can throw it with its own context once the Embree call returns.
inline void record_first_error(void* user, RTCError code, const char* message) {
  auto* first = static_cast<std::string*>(user);
  if (first->empty()) first->assign("Embree error " + std::to_string(static_cast<int>(code)) + ": " + (message ? message : ""));
}

}  // namespace cdp::embree
