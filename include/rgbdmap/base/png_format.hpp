#pragma once

#include <cstdint>
#include <cstdlib>

// What the PNG decoder and encoder share of the format.
namespace rgbdmap {

// The eight bytes every PNG file begins with.
constexpr std::uint8_t kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

// PNG's Paeth predictor of a byte from its left (a), upper (b) and upper-left (c) neighbours:
// whichever is nearest a + b - c, ties to a, then b. Branch-free by masks: photos and noisy renders
// make the choice unpredictable, and a ternary here compiles to branches that mispredict on about
// every other pixel (twice the time to decode a rendered colour image); masks also let the
// encoder's loop over a row vectorise.
inline int pngPaeth(int a, int b, int c) {
  const int pa = std::abs(b - c);  // |p - a| with p = a + b - c
  const int pb = std::abs(a - c);
  const int pc = std::abs(a + b - 2 * c);
  const int a_nearer = -static_cast<int>(pa <= pb);  // all ones when a is at least as near as b
  const int nearer = (a & a_nearer) | (b & ~a_nearer);
  const int nearest = (pa & a_nearer) | (pb & ~a_nearer);
  const int not_c = -static_cast<int>(nearest <= pc);
  return (nearer & not_c) | (c & ~not_c);
}

}  // namespace rgbdmap
