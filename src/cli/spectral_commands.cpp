// `polrig spectral kd`: the spectral model of why the integrating sphere's lamp and the sky give
// different kd (docs/physics.md, "The spectral model of kd").
#include <algorithm>
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "cli.h"
#include "polrig/io/csv.h"
#include "polrig/io/measured.h"
#include "polrig/io/plot.h"
#include "polrig/io/spectrum_csv.h"
#include "polrig/spectral/effective_degree.h"
#include "polrig/spectral/kd.h"
#include "polrig/spectral/sources.h"

namespace polrig::cli {
namespace fs = std::filesystem;

namespace {

struct SpectralKdOptions {
  std::string films, response, response_column = "response", sun, sun_column = "extraterrestrial";
  double lamp_K = kIlluminantA_K, sun_K = kSunBlackbody_K;
  std::vector<double> tau_m_scale;
};

constexpr int kChannels = 6;

// spectra.csv: kd_spectra's columns.
CsvTable spectra_table(const KdSpectra& k) {
  CsvTable t({"wavelength_nm", "tau_M", "tau_m", "film_d", "response", "lamp_weight", "sky_weight"});
  t.allow_undefined("film_d");  // τM + τm = 0: no light passes
  for (std::size_t i = 0; i < k.wavelength_nm.size(); ++i)
    t.add_row({k.wavelength_nm[i], k.tau_M[i], k.tau_m[i], k.film_d[i], k.response[i],
               k.lamp_weight[i], k.sky_weight[i]});
  return t;
}

void run_spectral_kd(const SpectralKdOptions& o, const OutputOptions& out) {
  // Everything is read and checked before the output folder is opened.
  if (!o.tau_m_scale.empty() && o.tau_m_scale.size() != kChannels)
    throw DataError(fmt::format("--tau-m-scale: {} values; expected {} (one per channel) or none",
                                o.tau_m_scale.size(), kChannels));
  std::vector<double> scale = o.tau_m_scale;
  if (scale.empty()) scale.assign(kChannels, 1.0);

  const FilmSpectra film = read_film_csv(o.films);
  const Spectrum response = read_spectrum_csv(o.response, o.response_column);
  const Spectrum sun = o.sun.empty() ? blackbody(o.sun_K, response.min_nm(), response.max_nm())
                                     : read_spectrum_csv(o.sun, o.sun_column);
  SpectralKd result;
  try {
    result = spectral_kd(film, response, o.lamp_K, sun, scale,
                         {"--films " + o.films, "--sun " + o.sun, "--tau-m-scale"});
  } catch (const SpectrumError& e) {
    throw DataError(e.what());
  }

  CsvTable kd({"channel", "tau_m_scale", "d_eff_lamp", "kd_lamp", "d_eff_sky", "kd_sky",
               "kd_sky_minus_lamp"});
  for (std::size_t c = 0; c < result.channels.size(); ++c) {
    const ChannelKd& k = result.channels[c];
    kd.add_row({double(c + 1), scale[c], k.lamp.d_eff, k.lamp.kd(), k.sky.d_eff, k.sky.kd(),
                k.kd_sky_minus_lamp()});
  }
  const CsvTable spectra = spectra_table(result.spectra);

  OutputDir dir = out.open();
  write_text_file(dir.staging() / "kd.csv", kd.text());
  write_text_file(dir.staging() / "spectra.csv", spectra.text());
  std::vector<DatasetFile> files{
      {"kd.csv", 1, "per channel: leakage scale, d_eff and kd = d_eff - 1 under the lamp and the "
                    "sky, and the sky-minus-lamp kd shift"},
      {"spectra.csv", 1, "on a 1 nm grid over the response's band: films, their degree, the "
                         "response, and each source's S*R normalised to 1 at its peak"}};
  if (out.plots()) {
    Plot fig;
    fig.png = "spectra.png";
    fig.title = fmt::format("Weights S·R of the lamp ({} K) and of the sky, and the film's degree",
                            o.lamp_K);
    fig.xlabel = "wavelength (nm)";
    fig.ylabel = "S·R, normalised to 1 at the peak";
    fig.y2label = "film (τM − τm)/(τM + τm)";
    fig.series = {{"spectra.csv", "$wavelength_nm:$lamp_weight", fmt::format("lamp, blackbody {} K", o.lamp_K)},
                  {"spectra.csv", "$wavelength_nm:$sky_weight",
                   o.sun.empty() ? fmt::format("sky: blackbody {} K × λ⁻⁴", o.sun_K)
                                 : fmt::format("sky: {} × λ⁻⁴", o.sun_column),
                   "lines lw 2 lc rgb '#1f77b4'"},
                  {"spectra.csv", "$wavelength_nm:$film_d", "film degree (right axis)",
                   "lines lw 2 dt 2 lc rgb '#2ca02c'", true}};
    fig.series[0].style = "lines lw 2 lc rgb '#d62728'";
    fig.extra = "set yrange [0:1.05]\nset y2range [0:1.0]\nset key inside right bottom";
    render_plots(dir.staging(), "plots.gp", {fig});
    files.push_back({"spectra.png", 1, "the two sources' weights S·R and the film's degree"});
  }
  std::vector<std::string> inputs{o.films, o.response};
  if (!o.sun.empty()) inputs.push_back(o.sun);
  write_manifest(dir.staging(), {command_line(), nullptr, files, inputs});
  finish(dir);
}

}  // namespace

std::vector<Command> add_spectral_commands(CLI::App& root) {
  std::vector<Command> commands;
  auto* spectral = root.add_subcommand("spectral", "the spectral model of kd (lamp against sky)");
  spectral->require_subcommand(1);
  auto* app = spectral->add_subcommand(
      "kd", "each channel's effective degree and kd under the sphere's lamp and under the sky");
  auto o = std::make_shared<SpectralKdOptions>();
  auto out = std::make_shared<OutputOptions>();
  app->add_option("--films", o->films, "film transmittances: CSV with wavelength_nm,tau_M,tau_m")
      ->required()->check(CLI::ExistingFile);
  app->add_option("--response", o->response,
                  "filter x photodiode responsivity: CSV with wavelength_nm and --response-column; "
                  "its wavelengths set the band")
      ->required()->check(CLI::ExistingFile);
  app->add_option("--response-column", o->response_column, "the response file's value column")
      ->capture_default_str();
  app->add_option("--lamp-temperature", o->lamp_K, "the lamp's blackbody temperature (CIE A: 2856)")
      ->check(finite_range(kMinTemperature_K, kMaxTemperature_K, "K"))->capture_default_str();
  auto* sun = app->add_option("--sun", o->sun,
                              "solar spectrum: CSV with wavelength_nm and --sun-column "
                              "(e.g. data/spectra/astm-g173.csv); default a blackbody")
                  ->check(CLI::ExistingFile);
  app->add_option("--sun-column", o->sun_column, "the solar file's value column")
      ->capture_default_str()->needs(sun);
  app->add_option("--sun-temperature", o->sun_K, "the blackbody sun's temperature, without --sun")
      ->check(finite_range(kMinTemperature_K, kMaxTemperature_K, "K"))->capture_default_str()
      ->excludes(sun);
  app->add_option("--tau-m-scale", o->tau_m_scale,
                  "six factors on each channel's leakage tau_m, comma-separated (default all 1)")
      ->delimiter(',')->check(finite_range(1e-6, 1e3));
  out->add_to(*app);
  commands.push_back({app, [=] { run_spectral_kd(*o, *out); }});
  return commands;
}

}  // namespace polrig::cli
