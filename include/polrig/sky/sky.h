#pragma once
// A sky: where and when it is seen, how the sun is computed and how the sky is modelled. It is
// the `sky:` block of a rig file (source.model: sky) and the input of `polrig sky`.
#include "polrig/sky/rayleigh.h"
#include "polrig/sky/sun.h"

namespace polrig {

struct Sky {
  Site site;                              // default: the W19 roof in Dalian
  UtcTime first_stop{1542355780.0};       // 2018-11-16T08:09:40Z, W19 Outdoor1's first stop
  SunSettings sun;
  SkyModel model;
};

}  // namespace polrig
