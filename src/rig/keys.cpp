#include "polrig/rig/keys.h"

#include <cmath>

#include <fmt/format.h>

namespace polrig {
namespace {

using K = RigKey::Kind;

bool positive(double v) { return v > 0.0; }
bool non_negative(double v) { return v >= 0.0; }
bool any_angle(double) { return true; }
bool open_unit(double v) { return v > 0.0 && v < 1.0; }
bool polarizer_kd(double v) { return v > -1.0 && v <= 0.0; }

RigKey real(std::string_view path, std::string_view unit, std::string_view expects,
            std::string_view doc, double& (*ref)(Rig&), bool (*ok)(double)) {
  RigKey k{path, K::Real, unit, expects, doc};
  k.real = ref;
  k.valid_real = ok;
  return k;
}
RigKey array(std::string_view path, std::string_view unit, std::string_view expects,
             std::string_view doc, std::span<double> (*ref)(Rig&), bool (*ok)(double)) {
  RigKey k{path, K::RealArray, unit, expects, doc};
  k.array = ref;
  k.valid_real = ok;
  return k;
}

std::vector<RigKey> make_keys() {
  std::vector<RigKey> keys;
  // --- device -------------------------------------------------------------------------
  keys.push_back(real("device.L_photo", "mm", "a length > 0",
                      "radius of the photodiode ring around the sensor centre O_S",
                      [](Rig& r) -> double& { return r.device.ring.L_photo; }, positive));
  keys.push_back(array("device.beta_deg", "deg", "6 finite angles",
                       "angle β_m of photodiode m on the ring, rig frame at θ_R = 0 "
                       "(x-axis from O_S through photodiode 1)",
                       [](Rig& r) { return std::span<double>(r.device.ring.beta_deg); },
                       any_angle));
  keys.push_back(array("device.film_axes_deg", "deg", "6 finite angles",
                       "nominal film axes in the sensor frame; they define the theory "
                       "parameters α_j = −2f_j, α_h = 180° − 2f_h",
                       [](Rig& r) { return std::span<double>(r.device.film_axis_deg); },
                       any_angle));
  keys.push_back(real("device.d", "", "a degree of polarization in (0, 1)",
                      "degree of linear polarization of the light reaching the sensor",
                      [](Rig& r) -> double& { return r.device.d; }, open_unit));
  keys.push_back(array("device.truth.alpha_deg", "deg", "6 finite angles",
                       "true installation angles α_m, doubled-angle domain (Eq. 15)",
                       [](Rig& r) { return std::span<double>(r.device.truth.alpha_deg); },
                       any_angle));
  keys.push_back(array("device.truth.k_mV", "mV", "3 finite offsets",
                       "true additive offsets k_i of the pair voltages (Eq. 15)",
                       [](Rig& r) { return std::span<double>(r.device.truth.k_mV); },
                       any_angle));
  keys.push_back(array("device.truth.kv", "", "3 gains > 0",
                       "true log-amplifier reference deviations kv_i (Eq. 15)",
                       [](Rig& r) { return std::span<double>(r.device.truth.kv); }, positive));
  keys.push_back(array("device.truth.kd", "", "6 values in (−1, 0]",
                       "true polarizer coefficients kd_m = (τM−τm)/(τM+τm) − 1 (Eq. 15)",
                       [](Rig& r) { return std::span<double>(r.device.truth.kd); },
                       polarizer_kd));
  {
    RigKey k{"device.truth_from", K::Text, "", "a path to a params.yaml",
             "load device.truth from a calibration's params.yaml (path relative to the rig "
             "file); excludes device.truth.*"};
    k.text = [](Rig& r) -> std::string& { return r.device.truth_from; };
    k.valid_text = [](std::string_view v) { return !v.empty(); };
    keys.push_back(k);
  }
  // --- source -------------------------------------------------------------------------
  {
    RigKey k{"source.model", K::Text, "", "\"cos4\" or \"traced\"",
             "source model: cos4 is the analytic E_0·cos⁴φ port; traced is the Embree-traced "
             "sphere of source.scene"};
    k.text = [](Rig& r) -> std::string& { return r.source.model; };
    k.valid_text = [](std::string_view v) { return v == "cos4" || v == "traced"; };
    keys.push_back(k);
  }
  {
    RigKey k{"source.scene", K::Text, "", "a path to a scene file",
             "traced: the scene (scenes/*.yaml), relative to the rig file; its port film gives "
             "the light's d and angle"};
    k.text = [](Rig& r) -> std::string& { return r.source.scene; };
    k.valid_text = [](std::string_view v) { return !v.empty(); };
    keys.push_back(k);
  }
  keys.push_back(real("source.L_o", "mm", "a length > 0 (at 0 the cos⁴ law gives no light off-axis)",
                      "distance from the port plane down to the photosensitive plane",
                      [](Rig& r) -> double& { return r.source.cos4.L_o; }, positive));
  keys.push_back(real("source.E_0", "W/m^2", "an irradiance > 0",
                      "irradiance on the port axis at the photosensitive plane",
                      [](Rig& r) -> double& { return r.source.cos4.E_0; }, positive));
  keys.push_back(real("source.polarizer_deg", "deg", "a finite angle",
                      "axis ψ_P of the port polarizer in the rig frame; θ = θ_R − ψ_P",
                      [](Rig& r) -> double& { return r.source.polarizer_deg; }, any_angle));
  // --- eccentricity -------------------------------------------------------------------
  keys.push_back(real("eccentricity.L_IS", "mm", "a length ≥ 0",
                      "offset of the port centre O_IS from the table centre O_R",
                      [](Rig& r) -> double& { return r.eccentricity.L_IS; }, non_negative));
  keys.push_back(real("eccentricity.alpha_IS", "deg", "a finite angle",
                      "direction of the port centre's offset",
                      [](Rig& r) -> double& { return r.eccentricity.alpha_IS; }, any_angle));
  keys.push_back(real("eccentricity.L_S", "mm", "a length ≥ 0",
                      "offset of the sensor centre O_S from O_R at θ_R = 0",
                      [](Rig& r) -> double& { return r.eccentricity.L_S; }, non_negative));
  keys.push_back(real("eccentricity.alpha_S", "deg", "a finite angle",
                      "direction of the sensor centre's offset at θ_R = 0",
                      [](Rig& r) -> double& { return r.eccentricity.alpha_S; }, any_angle));
  // --- schedule -----------------------------------------------------------------------
  keys.push_back(real("schedule.start_deg", "deg", "a finite angle", "first table stop",
                      [](Rig& r) -> double& { return r.schedule.start_deg; }, any_angle));
  keys.push_back(real("schedule.step_deg", "deg", "a step > 0", "table step between stops",
                      [](Rig& r) -> double& { return r.schedule.step_deg; }, positive));
  keys.push_back(real("schedule.stop_deg", "deg", "an angle ≥ schedule.start_deg",
                      "last table stop (included when reached by whole steps)",
                      [](Rig& r) -> double& { return r.schedule.stop_deg; }, any_angle));
  {
    RigKey k{"schedule.angles_deg", K::RealList, "deg", "a non-empty list of finite angles",
             "explicit table stops; replaces start/step/stop (give one or the other)"};
    k.list = [](Rig& r) -> std::vector<double>& { return r.schedule.angles_deg; };
    k.valid_real = any_angle;
    keys.push_back(k);
  }
  {
    RigKey k{"schedule.samples_per_stop", K::Integer, "", "an integer in [1, 100000]",
             "samples the sensor records at each stop (the paper averages 40)"};
    k.integer = [](Rig& r) -> int& { return r.schedule.samples_per_stop; };
    k.valid_integer = [](long long v) { return v >= 1 && v <= 100000; };
    keys.push_back(k);
  }
  // --- electronics --------------------------------------------------------------------
  keys.push_back(real("electronics.volts_per_decade", "V", "a gain > 0",
                      "log-amplifier scale (the 0.5 of Eq. 1)",
                      [](Rig& r) -> double& { return r.electronics.volts_per_decade; },
                      positive));
  {
    RigKey k{"electronics.adc_bits", K::Integer, "", "an integer in [2, 31]",
             "resolution of the signed ADC (Eq. 3 uses 2^(bits−1))"};
    k.integer = [](Rig& r) -> int& { return r.electronics.adc_bits; };
    k.valid_integer = [](long long v) { return v >= 2 && v <= 31; };
    keys.push_back(k);
  }
  keys.push_back(real("electronics.vref_V", "V", "a voltage > 0", "ADC reference voltage",
                      [](Rig& r) -> double& { return r.electronics.vref_V; }, positive));
  keys.push_back(real("electronics.noise_sigma_V", "V", "a standard deviation ≥ 0",
                      "Gaussian noise on each pair voltage, per sample, before the ADC",
                      [](Rig& r) -> double& { return r.electronics.noise_sigma_V; },
                      non_negative));
  // --- seed ---------------------------------------------------------------------------
  {
    RigKey k{"seed", K::Seed, "", "an unsigned 64-bit integer",
             "seed of every random stream; streams derive from (seed, stop, channel, sample)"};
    k.seed = [](Rig& r) -> std::uint64_t& { return r.seed; };
    keys.push_back(k);
  }
  return keys;
}

}  // namespace

const std::vector<RigKey>& rig_keys() {
  static const std::vector<RigKey> keys = make_keys();
  return keys;
}

const RigKey* find_rig_key(std::string_view path) {
  for (const RigKey& k : rig_keys())
    if (k.path == path) return &k;
  return nullptr;
}

std::optional<RigProblem> check_rig(const Rig& rig) {
  const Schedule& s = rig.schedule;
  if (s.angles_deg.empty()) {
    if (s.stop_deg < s.start_deg)
      return RigProblem{"schedule.stop_deg",
                        fmt::format("expected an angle ≥ schedule.start_deg ({}), got {}",
                                    s.start_deg, s.stop_deg),
                        "schedule.start_deg"};
    if ((s.stop_deg - s.start_deg) / s.step_deg > 1e6)
      return RigProblem{"schedule.step_deg", "expected at most 1e6 stops"};
  }
  for (int m = 0; m < 6; ++m) {
    // Eq. 15's brackets must stay positive for every θ: (1+kd_m)·d < 1.
    if ((1.0 + rig.device.truth.kd[m]) * rig.device.d >= 1.0)
      return RigProblem{"device.d", fmt::format("expected (1+kd_{})·d < 1, got {}", m + 1,
                                                (1.0 + rig.device.truth.kd[m]) * rig.device.d)};
  }
  return std::nullopt;
}

}  // namespace polrig
