#!/bin/sh
# Regenerate the example recordings shipped in features/examples/ (see its __init__.py): one clean, steady
# (period-1) recording of each state the verdict names, and one oil-whirl recording labelled as such.
# MODEL.md's plant at 1800 r/min, generator unbalance A = 0.05, 40 dB SNR, 1 µm 1X runout, seed 1;
# 8 probes (b1@45 … b4@135) at 2560 Hz, 40 revolutions after the transient. The shipped model gives each
# steady case its band, confident, with the clearance of its sidecar (350 µm, MODEL.md's c).
set -e
D=features/examples
steady() {  # name Δ format...
  name=$1; m=$2; shift 2
  for ext in "$@"; do
    rotordiag simulate --speed-rpm 1800 --misalignment "$m" --unbalance 0.05 --mechanism rigid --record-revs 40 \
      --probe-sample-rate-hz 2560 --snr-db 40 --runout-um 1 --seed 1 --probes-out "$D/$name.$ext" > /dev/null
  done
  echo '{"clearance_um": 350}' > "$D/$name.json"
}
steady aligned 0 csv h5
steady slight 0.1 csv
steady moderate 0.25 csv
steady severe 0.45 csv
# The whirl example: a pin coupling at Δ = 0.5 runs quasi-periodic at this speed — a 0.38X oil whirl dominates
# the orbit. It shows every reader format (CSV, HDF5, UFF 58b, a bare NPY with its sample rate in a sidecar).
for ext in csv h5; do
  rotordiag simulate --speed-rpm 1800 --misalignment 0.5 --unbalance 0.05 --record-revs 40 \
    --probe-sample-rate-hz 2560 --snr-db 40 --runout-um 1 --seed 1 --probes-out $D/whirl.$ext > /dev/null
done
rotordiag simulate --speed-rpm 1800 --misalignment 0.5 --unbalance 0.05 --record-revs 40 \
  --probe-sample-rate-hz 2560 --snr-db 40 --runout-um 1 --seed 1 --probes-out $D/whirl_2560hz.npy > /dev/null
echo '{"sample_rate_hz": 2560}' > $D/whirl_2560hz.json
rm -f $D/whirl.uff
rotordiag simulate --speed-rpm 1800 --misalignment 0.5 --unbalance 0.05 --record-revs 40 \
  --probe-sample-rate-hz 2560 --snr-db 40 --runout-um 1 --seed 1 --probes-out $D/whirl.uff > /dev/null
