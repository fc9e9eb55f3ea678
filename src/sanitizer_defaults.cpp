// Sanitizer defaults compiled into every rgbdmap executable. They only matter in sanitizer
// builds; in others the functions are never called.
//
// Third-party libraries we link are not instrumented. OpenNI2 locks and unlocks its global
// mutexes from static constructors/destructors in a way ThreadSanitizer reports as "unlock of an
// unlocked mutex" at process exit, before any of our code runs; those reports are about
// OpenNI2's internals, not our threads, so reports whose frames come from it are suppressed.
// Everything in our own code stays checked.

#if defined(__SANITIZE_ADDRESS__)
#include <opencv2/core/utility.hpp>

namespace {
// OpenCV runs its parallel loops on TBB's workers, which live until the process exits. When
// LeakSanitizer stops every thread at exit to look for leaks, a worker still going away can crash
// its tracer ("Tracer caught signal 11 ... LeakSanitizer has encountered a fatal error",
// google/sanitizers#1353): a test that passed then fails (once in CI, 2026-12-06, on ORB
// features). Under ASan, OpenCV's loops run on the thread that calls them, so no worker exists.
const bool kOpenCvOnCallingThread = (cv::setNumThreads(1), true);
}  // namespace
#endif

extern "C" {

const char* __tsan_default_suppressions() {
  return "called_from_lib:libOpenNI2.so\n"
         "called_from_lib:libOpenNI.so\n"
         "called_from_lib:libusb-1.0.so\n"
         "race:libOpenNI2.so\n"
         "mutex:libOpenNI2.so\n"
         "deadlock:libOpenNI2.so\n"
         // OpenNI2's own drivers (recordings, PrimeSense cameras): their threads hand frames over
         // through libOpenNI2, so TSan sees neither their locks' order nor the handover. (Not
         // called_from_lib: OpenNI2 unloads its drivers at shutdown, which TSan forbids for those.)
         "race:libOniFile.so\n"
         "race:libPS1080.so\n"
         "race:libPSLink.so\n"
         "mutex:libOniFile.so\n"
         "deadlock:libOniFile.so\n"
         "mutex:libPS1080.so\n"
         "deadlock:libPS1080.so\n"
         // OpenCV's image decoding asks GDAL, which takes its mutexes in varying order.
         "called_from_lib:libgdal.so\n"
         "deadlock:libgdal.so\n"
         "mutex:libgdal.so\n";
}

const char* __tsan_default_options() { return "halt_on_error=1 second_deadlock_stack=1"; }

// Libraries that allocate global state once and never free it (not leaks of ours).
const char* __lsan_default_suppressions() {
  return "leak:libOpenNI2.so\n"
         "leak:libOpenNI.so\n"
         "leak:libusb-1.0.so\n"
         "leak:libOniFile.so\n"
         "leak:libPS1080.so\n"
         "leak:libPSLink.so\n"
         "leak:libvtk\n"
         "leak:libfontconfig\n"
         "leak:libgomp\n";
}

}  // extern "C"
