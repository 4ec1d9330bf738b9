// Commands that run the rig model: simulate, study cs, study adc, sweep, run, rig show/keys.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <optional>
#include <sstream>
#include <iostream>

#include <fmt/format.h>

#include "cli.h"
#include "polrig/calib/pipeline.h"
#include "polrig/calib/rig_options.h"
#include "polrig/rig/keys.h"
#include "polrig/sim/simulate.h"
#include "polrig/study/adc_limit.h"
#include "polrig/report/calibration_reports.h"
#include "polrig/study/cs.h"
#include "polrig/report/dofp_dataset.h"
#include "polrig/report/four_camera_dataset.h"
#include "polrig/sim/checkerboard.h"
#include "polrig/report/reports.h"
#include "polrig/report/sweep_report.h"
#include "polrig/io/plot.h"
#include "polrig/study/sweep.h"
#include "polrig/report/trace_report.h"
#include "polrig/io/scene_yaml.h"

namespace polrig::cli {
namespace fs = std::filesystem;

namespace {

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct EvenSteps : CLI::Validator {
  EvenSteps() : CLI::Validator("EVEN") {
    func_ = [](const std::string& s) -> std::string {
      long long v = 0;
      if (!CLI::detail::lexical_cast(s, v)) v = 0;  // not a whole number: refused as 0 is
      if (const auto problem = cs_steps_problem(v)) return *problem + ", got " + s;
      return {};
    };
  }
};

// The stops of a simulation as calibration input: the same type a measured CSV becomes.
std::vector<StopVoltages> stops_of(const Simulation& sim) {
  std::vector<StopVoltages> stops;
  for (std::size_t k = 0; k < sim.stops.size(); ++k)
    stops.push_back({sim.stops[k].theta_R_deg, sim.stops[k].V_mean, fmt::format("stop {}", k)});
  return stops;
}

CalibrationOptions calibration_options_for(const Rig& rig, CalibrationMethod m) {
  CalibrationOptions o = calibration_options(rig, rig.device.d, NoncontinuousRule{});
  o.method = m;
  o.d_a_source = "the rig's device.d";
  return o;
}

}  // namespace

std::vector<Command> add_rig_commands(CLI::App& root, int& threads) {
  std::vector<Command> commands;

  // ---- simulate
  {
    auto* app = root.add_subcommand("simulate", "synthetic measurements over the rig's table schedule");
    auto rig = std::make_shared<RigInput>();
    auto out = std::make_shared<OutputOptions>();
    auto samples = std::make_shared<bool>(false);
    rig->add_to(*app, true);
    out->add_to(*app);
    app->add_flag("--samples", *samples, "also write every quantized sample (samples.csv)");
    // A camera rig (an instrument that takes frames): the frames' storage, truth layers, analyzer.
    auto frames = std::make_shared<std::string>("every");
    auto truth_layers = std::make_shared<bool>(false);
    auto analyzer = std::make_shared<std::string>("image-plane");
    auto* frames_opt = app->add_option("--frames", *frames,
                                       "a camera rig: every frame, or the per-stop mean (stored exactly as the "
                                       "frames' sum, raw_sum)")
                           ->check(CLI::IsMember({"every", "mean"}))->capture_default_str();
    auto* layers_opt = app->add_flag("--truth-layers", *truth_layers,
                                     "a camera rig: also write each stop's S0, S1, S2, AoP, DoP");
    auto* analyzer_opt = app->add_option("--analyzer", *analyzer,
                                         "a camera rig: the micro-polarizers in the image plane or in front of the "
                                         "lens (spec §2.5)")
                             ->check(CLI::IsMember({"image-plane", "in-front"}))->capture_default_str();
    // A camera array (four-camera): which layers each stop's EXR holds.
    auto layers = std::make_shared<std::string>();
    auto* array_layers_opt = app->add_option("--layers", *layers,
                                       "a camera array: aop (AoP, DoP: what locate reads), fused (also S0, S1, "
                                       "S2) or all (also the four raw frames, which the calibration reads); "
                                       "default: all for a calibration rig (unpolarized levels or checkerboard "
                                       "views), else aop")
                           ->check(CLI::IsMember({"all", "fused", "aop"}));
    add_threads_option(*app, threads);
    commands.push_back({app, [=] {
      const LoadedRig r = rig->load();
      if (r.rig.instrument().has(Instrument::kCameraArray)) {
        if (*samples) throw RigError(fmt::format("--samples: device.kind {} takes frames, not samples", r.rig.device_kind));
        for (const CLI::Option* o : {frames_opt, analyzer_opt})
          if (o->count() > 0)
            throw RigError(fmt::format("{}: device.kind {} has no polarizer mosaic (a dofp-camera option)",
                                       o->get_name(), r.rig.device_kind));
        if (*truth_layers)
          throw RigError(fmt::format("--truth-layers: device.kind {} writes its truth in truth.yaml", r.rig.device_kind));
        FourCameraDatasetOptions o;
        o.previews = out->plots();
        o.layers = array_layers_opt->count() > 0 ? *parse_four_camera_layers(*layers)  // checked by IsMember
                                                 : default_four_camera_layers(r.rig);
        try {
          const FourCameraSimulator check(r.rig);  // refused before the folder is opened
          if (r.rig.checkerboard.views > 0) (void)checkerboard_poses(r.rig);  // the board placed, likewise
        } catch (const std::invalid_argument& e) {
          throw RigError(fmt::format("{}: {}", r.origin, e.what()));
        }
        OutputDir dir = out->open();
        write_manifest(dir.staging(), {command_line(), &r, report_four_camera_dataset(dir.staging(), r.rig, o, progress())});
        finish(dir);
        return;
      }
      if (array_layers_opt->count() > 0)
        throw RigError(fmt::format("--layers: device.kind {} is not a camera array", r.rig.device_kind));
      if (r.rig.instrument().has(Instrument::kUnitArray)) {
        for (const CLI::Option* o : {frames_opt, layers_opt, analyzer_opt})
          if (o->count() > 0)
            throw RigError(fmt::format("{}: device.kind {} takes no frames", o->get_name(), r.rig.device_kind));
        if (*samples) throw RigError(fmt::format("--samples: device.kind {} writes its units' mean voltages (units.csv)", r.rig.device_kind));
        simulate_unit_array(r, *out);
        return;
      }
      if (r.rig.instrument().has(Instrument::kMosaic)) {
        if (*samples) throw RigError(fmt::format("--samples: device.kind {} takes frames, not samples", r.rig.device_kind));
        DofpDatasetOptions o;
        o.storage = *frames == "mean" ? DofpFrameStorage::Sum : DofpFrameStorage::Every;
        o.truth_layers = *truth_layers;
        o.analyzer = *analyzer == "in-front" ? DofpAnalyzer::InFront : DofpAnalyzer::ImagePlane;
        o.previews = out->plots();
        try {
          const DofpSimulator check(r.rig, o.analyzer);  // refused before the folder is opened
        } catch (const std::invalid_argument& e) {
          throw RigError(fmt::format("{}: {}", r.origin, e.what()));
        }
        OutputDir dir = out->open();
        write_manifest(dir.staging(), {command_line(), &r, report_dofp_dataset(dir.staging(), r.rig, o, progress())});
        finish(dir);
        return;
      }
      for (const CLI::Option* o : {frames_opt, layers_opt, analyzer_opt})
        if (o->count() > 0)
          throw RigError(fmt::format("{}: device.kind {} takes no frames", o->get_name(), r.rig.device_kind));
      OutputDir dir = out->open();
      const Simulation sim = simulate(r.rig, *samples, progress());
      write_manifest(dir.staging(), {command_line(), &r, report_simulation(dir.staging(), sim, out->plots())});
      finish(dir);
    }});
  }

  auto* study = root.add_subcommand("study", "studies of the rig");
  study->require_subcommand(1);

  // ---- study cs
  {
    auto* app = study->add_subcommand("cs", "central-symmetry study over a full turn (Figs. 8-9)");
    auto rig = std::make_shared<RigInput>();
    auto out = std::make_shared<OutputOptions>();
    auto steps = std::make_shared<int>(kDefaultCsSteps);
    rig->add_to(*app, true);
    out->add_to(*app);
    app->add_option("--steps", *steps, "table angles per turn (even)")->check(EvenSteps())->capture_default_str();
    add_threads_option(*app, threads);
    commands.push_back({app, [=] {
      const LoadedRig r = rig->load();
      require_instrument(r.rig, Instrument::kPairVoltages, "study cs", r.origin);
      OutputDir dir = out->open();
      const CsStudy s = cs_study(r.rig, CsTurn(*steps), progress());
      write_manifest(dir.staging(), {command_line(), &r, report_cs_study(dir.staging(), s, out->plots())});
      finish(dir);
    }});
  }

  // ---- study adc
  {
    auto* app = study->add_subcommand("adc", "ADC accuracy limit against d (Fig. 6)");
    auto rig = std::make_shared<RigInput>();
    auto out = std::make_shared<OutputOptions>();
    auto d_list = std::make_shared<std::string>(kDefaultAdcD);
    auto step = std::make_shared<double>(kDefaultAdcStep);
    rig->add_to(*app, false);
    out->add_to(*app);
    app->add_option("--d", *d_list, "degrees of polarization: a,b,c or start:stop:count")->capture_default_str();
    app->add_option("--step", *step, "θ step in degrees")->check(finite_range(kMinAdcStep, kMaxAdcStep, "deg"))->capture_default_str();
    add_threads_option(*app, threads);
    commands.push_back({app, [=] {
      // Electronics and film axes come from the rig; without one, from the default rig.
      const LoadedRig r = rig->load();
      require_instrument(r.rig, Instrument::kPairVoltages, "study adc", r.origin);
      const std::vector<double> ds = parse_d_list(*d_list);
      if (const auto problem = adc_work_problem(ds.size(), *step)) throw RigError("--d, --step: " + *problem);
      OutputDir dir = out->open();
      const auto limits = adc_accuracy_limits(ds, r.rig.electronics, r.rig.device.film_axis_deg, *step, progress());
      const auto files = report_adc_limits(dir.staging(), limits, out->plots());
      write_manifest(dir.staging(), {command_line(), &r, files});
      finish(dir);
    }});
  }

  // ---- sweep
  {
    auto* app = root.add_subcommand("sweep", "the CS study over a grid of rig keys (Figs. 10-12)");
    auto rig = std::make_shared<RigInput>();
    auto out = std::make_shared<OutputOptions>();
    auto grids = std::make_shared<std::vector<std::string>>();
    auto steps = std::make_shared<int>(kDefaultCsSteps);
    rig->add_to(*app, true);
    out->add_to(*app);
    app->add_option("--grid", *grids, "key=start:stop:count (repeatable: the product grid)")
        ->required()
        ->type_name("KEY=START:STOP:COUNT")
        ->allow_extra_args(false);
    app->add_option("--steps", *steps, "table angles per turn (even)")->check(EvenSteps())->capture_default_str();
    auto csv = std::make_shared<bool>(false);
    auto resume = std::make_shared<bool>(false);
    app->add_flag("--csv", *csv, "also write sweep.csv (one row per grid point; large)");
    app->add_flag("--resume", *resume, "continue an interrupted sweep into the same folder (same arguments)");
    add_threads_option(*app, threads);
    commands.push_back({app, [=] {
      // Every rank loads and checks the same input (the same verdict everywhere); rank 0 alone
      // prints, opens and writes the output, and receives every block (docs/scale.md).
      const Ranks& world = ranks();
      std::optional<LoadedRig> loaded;
      std::vector<GridAxis> axes;
      on_every_rank([&] {  // a rank that cannot read the rig (another node's files) stops all
        loaded.emplace(rig->load());
        require_instrument(loaded->rig, Instrument::kPairVoltages, "sweep", loaded->origin);
        for (const std::string& g : *grids) axes.push_back(GridAxis::parse(g));
        check_grid(loaded->rig, axes);
      });
      const LoadedRig& r = *loaded;
      if (world.is_root())
        for (const RigKey* key : axes_the_cs_study_ignores(axes))
          std::cerr << fmt::format("polrig: note: the CS study does not depend on '{}'; every "
                                   "row along that axis will be the same\n", key->path);
      on_rank_0([&] {
        if (axes.size() <= 2 && out->plots() && !gnuplot_available())
          throw std::runtime_error("gnuplot is needed for the PNG plots and was not found; install it "
                                   "(scripts/setup-deps.sh) or pass --no-plots");
      });
      SweepFolder folder{out->out, out->force, *csv, out->plots(), *resume, command_line(), "-o/--out " + out->out};
      folder.ranks = &world;
      const fs::path written = sweep_to_folder(r, axes, *steps, folder, progress());
      if (!world.is_root()) return;
      end_progress_line();
      std::cout << "wrote " << written.string() << "\n";
    }, true});
  }

  // ---- run: the main job
  {
    auto* app = root.add_subcommand(
        "run", "the main job: simulate the indoor calibration run, calibrate it three ways, the "
               "CS study and the ADC limits, into one folder");
    auto rig = std::make_shared<RigInput>();
    auto out = std::make_shared<OutputOptions>();
    rig->add_to(*app, true);
    out->add_to(*app);
    add_threads_option(*app, threads);
    commands.push_back({app, [=] {
      const LoadedRig r = rig->load();
      require_instrument(r.rig, Instrument::kPairVoltages, "run", r.origin);
      if (r.rig.light->has(Source::kTimeDependent))
        throw RigError(fmt::format("{}: polrig run is the indoor job (CS calibration of a fixed "
                                   "light); this rig's light is the sky: use polrig simulate, then "
                                   "polrig calibrate DIR --method nc --drift per-stop", r.origin));
      OutputDir dir = out->open();
      const Progress p = progress();
      const Simulation sim = simulate(r.rig, false, p);
      std::vector<CalibrationResult> calibrations;
      for (CalibrationMethod m : kAllMethods) {
        try {
          calibrations.push_back(calibrate(stops_of(sim), calibration_options_for(r.rig, m)));
        } catch (const CalibrationError& e) {
          throw CalibrationError(fmt::format("calibration type {} of the simulated run: {}", method_name(m), e.what()));
        }
        if (!calibrations.back().usable())
          throw CalibrationError(fmt::format("calibration type {} of the simulated run: the fit is "
                                             "not usable: {}", method_name(m),
                                             calibrations.back().fit.summary.brief_report()));
      }
      const CsStudy cs = cs_study(r.rig, CsTurn(kDefaultCsSteps), p);
      std::vector<double> ds;
      for (int k = 1; k <= 19; ++k) ds.push_back(k / 20.0);
      const std::vector<AdcLimit> limits = adc_accuracy_limits(ds, r.rig.electronics, r.rig.device.film_axis_deg, kDefaultAdcStep);

      const fs::path base = dir.staging();
      for (const char* sub : {"simulate", "calibration", "cs", "adc"}) fs::create_directory(base / sub);
      write_manifest(base / "simulate", {command_line(), &r, report_simulation(base / "simulate", sim, out->plots())});
      std::vector<DatasetFile> cal_files = report_calibration_comparison(base / "calibration", calibrations, out->plots());
      for (const CalibrationResult& c : calibrations) {
        const fs::path d = base / "calibration" / std::string(method_name(c.method));
        fs::create_directory(d);
        write_manifest(d, {command_line(), &r, report_calibration(d, c, calibration_options_for(r.rig, c.method), out->plots())});
      }
      write_manifest(base / "calibration", {command_line(), &r, cal_files});
      write_manifest(base / "cs", {command_line(), &r, report_cs_study(base / "cs", cs, out->plots())});
      write_manifest(base / "adc", {command_line(), &r, report_adc_limits(base / "adc", limits, out->plots())});
      finish(dir);

      std::cout << "Calibration of the simulated run, accuracy of θ_sec (degrees):\n";
      for (const CalibrationResult& c : calibrations)
        std::cout << fmt::format("  {:8s} ±{:.5f}\n", method_name(c.method), c.accuracy[kThetaSec].accuracy_deg());
      std::cout << "CS study at the rig's eccentricity (mV):\n"
                << "  pair     BSD       ASD   mean_br   mean_mr     Eq. 6\n";
      for (int i = 0; i < 3; ++i) {
        const CsPairSummary& s = cs.summary[i];
        std::cout << fmt::format("  {:4d} {:9.5f} {:9.5f} {:9.5f} {:9.5f} {:9.5f}\n", i + 1, s.bsd_mV,
                                 s.asd_mV, s.mean_br_mV, s.mean_mr_mV, s.eq6_mV);
      }
    }});
  }

  // ---- trace: the sphere solve of a scene
  {
    auto* app = root.add_subcommand("trace", "trace a scene's integrating sphere (Embree) and the light below its port");
    auto scene = std::make_shared<std::string>();
    auto out = std::make_shared<OutputOptions>();
    auto photons = std::make_shared<std::optional<long long>>();
    app->add_option("SCENE", *scene, "scene file (YAML), e.g. scenes/jf500.yaml")->required();
    app->add_option("--photons", *photons, "photons for the sphere solve (default: the scene's trace.photons)")
        ->check(CLI::Range(1000LL, 100000000000LL));
    out->add_to(*app);
    add_threads_option(*app, threads);
    commands.push_back({app, [=] {
      SceneSpec s = load_scene(*scene);
      if (const auto problem = set_trace_photons(s.trace, *photons))
        throw RigError(fmt::format("--photons {}: {}", **photons, *problem));
      OutputDir dir = out->open();
      const auto t0 = std::chrono::steady_clock::now();
      LightOrigin light;
      Manifest m{command_line(), nullptr, trace_scene(dir.staging(), s, out->plots(), progress(), &light), {*scene}};
      m.light = light;
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      write_manifest(dir.staging(), m);
      finish(dir);
      std::cout << read_text(dir.destination() / "trace_summary.yaml")
                << fmt::format("seconds: {:.1f}\n", seconds);
    }});
  }

  // ---- rig show / rig keys
  auto* rig_app = root.add_subcommand("rig", "inspect rig files");
  rig_app->require_subcommand(1);
  {
    auto* app = rig_app->add_subcommand("show", "print the effective rig (file + overrides + defaults)");
    auto rig = std::make_shared<RigInput>();
    rig->add_to(*app, true);
    commands.push_back({app, [=] { std::cout << rig_to_yaml(rig->load().rig); }});
  }
  {
    auto* app = rig_app->add_subcommand("keys", "print every rig key as a Markdown table");
    commands.push_back({app, [] {
      Rig defaults;
      std::cout << "| key | unit | default | accepts | meaning | why this range | read by | sources | instruments |\n"
                   "|---|---|---|---|---|---|---|---|---|\n";
      for (const RigKey& k : rig_keys()) {
        std::string def;
        using K = RigKey::Kind;
        switch (k.kind) {
          case K::Real: def = fmt::format("{}", k.real(defaults)); break;
          case K::Integer: def = fmt::format("{}", k.integer(defaults)); break;
          case K::Seed: def = fmt::format("{}", k.seed(defaults)); break;
          case K::Text: def = k.text(defaults).empty() ? "(none)" : k.text(defaults); break;
          case K::RealArray: def = fmt::format("[{}]", fmt::join(k.array(defaults), ", ")); break;
          case K::RealList:
            def = k.list(defaults).empty() ? "(none)" : fmt::format("[{}]", fmt::join(k.list(defaults), ", "));
            break;
          case K::Bool: def = k.boolean(defaults) ? "true" : "false"; break;
        }
        std::cout << fmt::format("| `{}` | {} | {} | {} | {} | {} | {} | {} | {} |\n", k.path, k.unit, def, k.expects,
                                 k.doc, k.why, k.studies_text(), k.sources.empty() ? "all" : k.sources,
                                 k.instruments.empty() ? "all" : k.instruments);
      }
    }});
  }
  return commands;
}

}  // namespace polrig::cli
