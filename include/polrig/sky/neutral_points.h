#pragma once
// The neutral points of the vector-RT sky on its solar meridian (spec skies.md §1, §3): where the
// polarization vanishes as it turns from perpendicular to the scattering plane ("positive", the
// single-scattering sense) to parallel ("negative"). On the solar meridian U = 0 by symmetry, so
// they are the zeros of Q (polrig's frame: Q > 0 along e_θ, in the meridian plane) found along it.
#include <optional>

#include "polrig/sky/rayleigh.h"
#include "polrig/sky/vector_rt.h"

namespace polrig {

// Angular distances along the solar meridian, degrees: Babinet above the sun (towards the zenith,
// over it if need be), Brewster below it, Arago above the antisun. Empty where the point is absent
// or below the horizon. The single-scattering sky has none (its Q < 0 everywhere off the sun's line).
struct NeutralPoints {
  double sun_el_deg = 0;
  std::optional<double> babinet_deg, brewster_deg, arago_deg;
};

// Each point bracketed on the rig's interpolated sky (0.1° steps along the meridian), the bracket
// then found again on exact solves (solve_vector_rt at the point's view) within a step either way
// and the point refined there to 1e-4° by Brent's method, so that the interpolation's error does
// not move it; a sign change of the interpolated sky that the exact sky does not have there is
// passed over. Throws std::invalid_argument for settings or a sun elevation the vector-RT sky
// refuses (min_sun_elevation_deg).
NeutralPoints vector_rt_neutral_points(const VectorRtSettings& s, double sun_el_deg);

// The neutral points of any sky model, what `sky neutral-points` writes: the vector-RT sky's
// (above); Berry's at its distances (Babinet δ_Ba; Brewster δ_Br where it stands above the horizon,
// else Arago, its antipode, δ_Br above the antisun); none for single scattering. Throws as the
// model's sky does for a sun it refuses.
NeutralPoints sky_neutral_points(const SkyModel& model, double sun_el_deg);

}  // namespace polrig
