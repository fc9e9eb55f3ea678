#pragma once

// RGBDMAP_VECTOR_CLONES before a function compiles it for x86-64-v3 (AVX2, FMA) as well as for
// the baseline, the CPU picking one at load time: a loop over floats then takes 8 per
// instruction instead of 4. For the few loops that most of a frame's time goes to.
//
// Not in sanitizer builds: the clones' resolver runs while the program is being loaded, before
// the sanitizer's runtime is ready (ThreadSanitizer crashes there).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__SANITIZE_THREAD__) && \
    !defined(__SANITIZE_ADDRESS__)
#define RGBDMAP_VECTOR_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define RGBDMAP_VECTOR_CLONES
#endif
