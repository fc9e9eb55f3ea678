#include "rgbdmap/mapping/keyframe_selector.hpp"

namespace rgbdmap {

KeyframeSelector makeKeyframeSelector(const KeyframeOptions& keyframe, const PoseOptions& pose) {
  const std::string policy = effectiveKeyframePolicy(keyframe, pose);
  return KeyframeSelector(policy == "motion" ? KeyframeSelector::Policy::kMotion
                          : policy == "both" ? KeyframeSelector::Policy::kBoth
                                             : KeyframeSelector::Policy::kInterval,
                          keyframe);
}

}  // namespace rgbdmap
