// The target that owns the precompiled third-party headers (RGBDMAP_PCH in CMakeLists.txt):
// CMake builds a precompiled header for a target with at least one source, and the other targets
// reuse it.
