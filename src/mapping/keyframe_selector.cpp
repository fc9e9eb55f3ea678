#include "rgbdmap/mapping/keyframe_selector.hpp"

namespace rgbdmap {

KeyframeSelector makeKeyframeSelector(const Config& c) {
  const std::string policy = effectiveKeyframePolicy(c);
  KeyframeSelector s;
  s.policy = policy == "motion" ? KeyframeSelector::Policy::kMotion
             : policy == "both" ? KeyframeSelector::Policy::kBoth
                                : KeyframeSelector::Policy::kInterval;
  s.every_n = c.keyframe_every_n;
  s.min_translation = c.keyframe_min_translation;
  s.min_rotation = c.keyframe_min_rotation;
  return s;
}

}  // namespace rgbdmap
