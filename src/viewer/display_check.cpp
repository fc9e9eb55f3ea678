#include "rgbdmap/viewer/display_check.hpp"

#include <GL/glx.h>
#include <X11/Xlib.h>

#include <cstdlib>

namespace rgbdmap {

bool displayAvailable(std::string& why) {
  const char* name = std::getenv("DISPLAY");
  if (!name || !*name) {
    why = "DISPLAY is not set";
    return false;
  }
  Display* display = XOpenDisplay(name);
  if (!display) {
    why = std::string("cannot connect to the display ") + name;
    return false;
  }
  int error_base = 0, event_base = 0;
  const bool glx = glXQueryExtension(display, &error_base, &event_base);
  XCloseDisplay(display);
  if (!glx) {
    why = std::string("the display ") + name + " has no OpenGL (GLX)";
    return false;
  }
  return true;
}

}  // namespace rgbdmap
