#include "xvfb_server.hpp"

// clang-format off
#include "test_support.hpp"
// Xlib last: its macros (Success, None, Bool) clash with Eigen and GoogleTest.
#include <X11/Xlib.h>
#include <X11/Xutil.h>
// clang-format on
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>

namespace rgbdmap::test {
namespace {

Display* dpy(void* display) { return static_cast<Display*>(display); }

int ignoreXErrors(Display*, XErrorEvent*) { return 0; }  // e.g. a window that just closed

}  // namespace

// Xvfb tells the display number it chose on a pipe once it accepts connections.
XvfbServer::XvfbServer() {
  if (run("command -v Xvfb >/dev/null 2>&1") != 0) {
    why_ = "Xvfb is not installed (Debian package xvfb; scripts/setup.sh installs it)";
    return;
  }
  int fds[2];
  if (::pipe(fds) != 0) {
    why_ = "no pipe for Xvfb";
    return;
  }
  pid_ = ::fork();
  if (pid_ == 0) {
    ::close(fds[0]);
    const std::string fd = std::to_string(fds[1]);
    ::execlp("Xvfb", "Xvfb", "-displayfd", fd.c_str(), "-screen", "0", "1280x800x24", "-nolisten",
             "tcp", static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  ::close(fds[1]);
  std::string number;
  pollfd p{fds[0], POLLIN, 0};
  char c = 0;
  while (::poll(&p, 1, 60'000) == 1 && ::read(fds[0], &c, 1) == 1 && c != '\n') number += c;
  ::close(fds[0]);
  if (number.empty()) {
    why_ = "Xvfb did not start";
    return;
  }
  const std::string name = ":" + number;
  ::setenv("DISPLAY", name.c_str(), 1);
  XSetErrorHandler(ignoreXErrors);
  display_ = XOpenDisplay(name.c_str());
  if (!display_) why_ = "cannot connect to Xvfb on " + name;
}

XvfbServer::~XvfbServer() {
  if (display_) XCloseDisplay(dpy(display_));
  if (pid_ > 0) {
    ::kill(pid_, SIGTERM);
    ::waitpid(pid_, nullptr, 0);
  }
}

XWindow XvfbServer::findWindow(const std::string& prefix) const {
  Display* d = dpy(display_);
  Window root = DefaultRootWindow(d), parent = 0, *children = nullptr;
  unsigned int count = 0;
  Window found = 0;
  if (!XQueryTree(d, root, &root, &parent, &children, &count)) return 0;
  for (unsigned int i = 0; i < count && !found; ++i) {
    char* name = nullptr;
    if (XFetchName(d, children[i], &name) && name) {
      if (std::string(name).rfind(prefix, 0) == 0) found = children[i];
      XFree(name);
    }
  }
  if (children) XFree(children);
  return found;
}

void XvfbServer::pressKey(XWindow window, char key) const {
  Display* d = dpy(display_);
  XEvent e{};
  e.xkey.type = KeyPress;
  e.xkey.display = d;
  e.xkey.window = window;
  e.xkey.root = DefaultRootWindow(d);
  e.xkey.time = CurrentTime;
  e.xkey.x = e.xkey.y = 10;
  e.xkey.same_screen = True;
  e.xkey.keycode = XKeysymToKeycode(d, static_cast<KeySym>(key));  // Latin-1 keysyms = ASCII
  XSendEvent(d, window, True, KeyPressMask, &e);
  e.xkey.type = KeyRelease;
  XSendEvent(d, window, True, KeyReleaseMask, &e);
  XFlush(d);
}

void XvfbServer::closeWindow(XWindow window) const {
  Display* d = dpy(display_);
  XEvent e{};
  e.xclient.type = ClientMessage;
  e.xclient.window = window;
  e.xclient.message_type = XInternAtom(d, "WM_PROTOCOLS", False);
  e.xclient.format = 32;
  e.xclient.data.l[0] = static_cast<long>(XInternAtom(d, "WM_DELETE_WINDOW", False));
  e.xclient.data.l[1] = CurrentTime;
  XSendEvent(d, window, False, NoEventMask, &e);
  XFlush(d);
}

cv::Mat XvfbServer::screenshot(XWindow window) const {
  Display* d = dpy(display_);
  XWindowAttributes a{};
  if (!XGetWindowAttributes(d, window, &a)) return {};
  XImage* image = XGetImage(d, window, 0, 0, static_cast<unsigned>(a.width),
                            static_cast<unsigned>(a.height), AllPlanes, ZPixmap);
  if (!image) return {};
  const auto channel = [](unsigned long pixel, unsigned long mask) {
    int shift = 0;
    while (mask && !(mask & 1)) {
      mask >>= 1;
      ++shift;
    }
    return static_cast<std::uint8_t>((pixel >> shift) & 0xff);
  };
  cv::Mat bgr(a.height, a.width, CV_8UC3);
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      const unsigned long pixel = XGetPixel(image, x, y);
      bgr.at<cv::Vec3b>(y, x) = {channel(pixel, image->blue_mask),
                                 channel(pixel, image->green_mask),
                                 channel(pixel, image->red_mask)};
    }
  XDestroyImage(image);
  return bgr;
}

}  // namespace rgbdmap::test
