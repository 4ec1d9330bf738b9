#!/usr/bin/env bash
# Regenerates the figures and numbers of docs/validation.md from the built polrig.
# Usage: bash scripts/make-validation.sh   (after scripts/build.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
p=./build/polrig
rig=rigs/wang2019-cs-simulation.yaml
out=$(mktemp -d)
img=docs/img
mkdir -p "$img"

$p study adc --d 0.05:0.95:91 -o "$out/adc"
$p study cs $rig --set eccentricity.L_S=0 -o "$out/fig8a"
$p study cs $rig --set eccentricity.L_IS=0 -o "$out/fig8b"
$p study cs $rig -o "$out/fig9"
$p sweep $rig --set eccentricity.L_IS=0 --grid eccentricity.alpha_S=0:359:360 --csv -o "$out/fig10"
$p sweep $rig --set eccentricity.alpha_S=240 --set eccentricity.L_IS=1 \
  --grid eccentricity.L_S=0.001:1:100 --csv -o "$out/fig11"
$p sweep $rig --set eccentricity.alpha_S=240 --set eccentricity.L_S=1 \
  --grid eccentricity.L_IS=0.001:1:100 --csv -o "$out/fig12"
$p sweep $rig --set eccentricity.alpha_S=240 \
  --grid eccentricity.L_IS=0.001:1:100 --grid eccentricity.L_S=0.001:1:100 --csv -o "$out/grid"
$p simulate rigs/wang2019-indoor.yaml -o "$out/simulate"
$p calibrate "$out/simulate" --method all -o "$out/calibrate"
$p study calibration rigs/wang2019-indoor.yaml --trials 1000 -o "$out/trials"
$p trace scenes/jf500.yaml -o "$out/trace"
$p study cs rigs/wang2019-indoor-traced.yaml -o "$out/traced_bare"
$p study cs rigs/wang2019-indoor-traced-lensed.yaml -o "$out/traced_lensed"
$p study cs rigs/wang2019-indoor.yaml -o "$out/cos4_indoor"
# Outdoors (W19 §5.1): Outdoor1 without noise, 16-bit ADC, calibrated with each drift mode.
$p simulate rigs/wang2019-outdoor1.yaml --set electronics.noise_sigma_V=0 -o "$out/outdoor1"
for d in none angle per-stop linear; do
  $p calibrate "$out/outdoor1" --method nc --drift $d -o "$out/outdoor1_$d"
done

cp "$out/adc/accuracy_limit.png" "$img/fig6_accuracy_limit.png"
cp "$out/fig8a/cs_pair1.png" "$img/fig8a_port_offset_pair1.png"
cp "$out/fig8b/cs_deviations.png" "$img/fig8b_sensor_offset.png"
cp "$out/fig9/cs_deviations.png" "$img/fig9_both_offsets.png"
cp "$out/fig10/sweep_expectation.png" "$img/fig10_alpha_S.png"
cp "$out/fig11/sweep_asd.png" "$img/fig11a_asd_vs_L_S.png"
cp "$out/fig11/sweep_expectation.png" "$img/fig11b_expectation_vs_L_S.png"
cp "$out/fig12/sweep_asd.png" "$img/fig12a_asd_vs_L_IS.png"
cp "$out/fig12/sweep_expectation.png" "$img/fig12b_expectation_vs_L_IS.png"
cp "$out/simulate/deviations.png" "$img/simulate_indoor_deviations.png"
cp "$out/calibrate/section/errors.png" "$img/fig16_errors_section.png"
cp "$out/calibrate/cs/errors.png" "$img/fig19a_errors_cs.png"
cp "$out/calibrate/cs-nc/errors.png" "$img/fig19b_errors_cs_nc.png"
cp "$out/calibrate/cs-nc/fit.png" "$img/fig17_fit_cs_nc.png"
cp "$out/calibrate/comparison.png" "$img/fig20_comparison.png"
cp "$out/calibrate/cs-nc/replacement.png" "$img/fig21_replacement.png"
cp "$out/trials/accuracy_cdf.png" "$img/calibration_trials_cdf.png"
cp "$out/trace/plane_profile.png" "$img/traced_plane_profile.png"
cp "$out/trace/wall_radiance.png" "$img/traced_wall_radiance.png"
cp "$out/traced_bare/cs_pair1.png" "$img/traced_bare_cs_pair1.png"
cp "$out/traced_lensed/cs_pair1.png" "$img/traced_lensed_cs_pair1.png"
for d in none angle per-stop; do cp "$out/outdoor1_$d/errors.png" "$img/outdoor1_errors_$d.png"; done

echo "== ADC limits (d = 0.05, 0.7) =="
grep -E '^(0.05|0.7),' "$out/adc/accuracy_limit.csv"
echo "== Fig. 8a / 8b / 9 summaries =="
for f in fig8a fig8b fig9; do echo "-- $f"; cat "$out/$f/summary.csv"; done
echo "== Fig. 10: alpha_S of the largest pair-1 CS deviation =="
awk -F, 'NR>1 && $6>m {m=$6; a=$1} END {print a, m}' "$out/fig10/sweep.csv"
echo "== Grid [0.001,1]^2: worst |Eq.6 - expectation|/expectation (%), ASD/BSD range (%) =="
awk -F, 'NR>1 { for (i=0;i<3;i++) { d=$(9+7*i); if (d<0) d=-d; if (d>w) w=d }
                 r=$(5); if (min==""||r<min) min=r; if (r>max) max=r }
         END { print "eq6 worst", w, "asd/bsd", min, max }' "$out/grid/sweep.csv"
echo "== Fig. 11 (L_IS = 1): ASD range over L_S =="
awk -F, 'NR>1 {a=$3; if (lo==""||a<lo) lo=a; if (a>hi) hi=a} END {print lo, hi, (hi-lo)/hi*100 "%"}' "$out/fig11/sweep.csv"
echo "== Fig. 12 (L_S = 1): expectation range over L_IS =="
awk -F, 'NR>1 {a=$6; if (lo==""||a<lo) lo=a; if (a>hi) hi=a} END {print lo, hi, (hi-lo)/hi*100 "%"}' "$out/fig12/sweep.csv"
echo "== Calibration of the simulated indoor run (accuracy, degrees) =="
cat "$out/calibrate/comparison.csv"
echo "== cs-nc parameters =="
cat "$out/calibrate/cs-nc/params.yaml"
echo "== Replacement (cs-nc) =="
cat "$out/calibrate/cs-nc/replacement.csv"
echo "== Monte-Carlo calibrations (1000 trials) =="
cat "$out/trials/summary.csv"
echo "== Traced source: trace summary, CS studies (cos4 indoor, bare, lensed) =="
cat "$out/trace/trace_summary.yaml"
for f in cos4_indoor traced_bare traced_lensed; do echo "-- $f"; cat "$out/$f/summary.csv"; done
for f in traced_bare traced_lensed; do
  echo "-- $f: largest and median per-pose standard error of dv_mr (mV)"
  awk -F, 'NR>1 {print $6}' "$out/$f/deviations.csv" | sort -g | awk '{v[NR]=$1} END {print v[NR], v[int((NR+1)/2)]}'
done
echo "== Spectral model of kd: channel 1's kd_lamp, kd_sky, sky - lamp =="
spec=data/spectra
spectral() { $p spectral kd --films $spec/sheet-polarizer-synthetic.csv --no-plots -o "$out/spectral_$1" "${@:2}" >/dev/null
             echo "-- $1: $(sed -n 2p "$out/spectral_$1/kd.csv" | cut -d, -f4,6,7)"; }
$p spectral kd --films $spec/sheet-polarizer-synthetic.csv --response $spec/blue-filter-photodiode-synthetic.csv \
  --sun $spec/astm-g173.csv -o "$out/spectral_plot" >/dev/null
cp "$out/spectral_plot/spectra.png" "$img/spectral-weights.png"
for R in blue-filter-photodiode-synthetic blue-filter-redleak-photodiode-synthetic; do
  spectral "$R-etr" --response $spec/$R.csv --sun $spec/astm-g173.csv
  spectral "$R-am15" --response $spec/$R.csv --sun $spec/astm-g173.csv --sun-column direct_am15
  spectral "$R-bb5778" --response $spec/$R.csv
done
for T in 2700 3000 3200; do
  spectral "lamp$T" --response $spec/blue-filter-photodiode-synthetic.csv --sun $spec/astm-g173.csv --lamp-temperature $T
done
$p spectral kd --films $spec/sheet-polarizer-synthetic.csv --response $spec/blue-filter-photodiode-synthetic.csv \
  --sun $spec/astm-g173.csv --tau-m-scale 0.25,0.5,0.75,1,1,1.1 --no-plots -o "$out/spectral_scaled" >/dev/null
cat "$out/spectral_scaled/kd.csv"
echo "== Outdoor1 (no noise, 16-bit ADC): nc with each drift mode (accuracy, parameters) =="
for d in none angle per-stop linear; do echo "-- $d"; grep -A4 '^accuracy_deg' "$out/outdoor1_$d/params.yaml"; grep -E '^(alpha_deg|kd):' "$out/outdoor1_$d/params.yaml"; done
rm -rf "$out"
