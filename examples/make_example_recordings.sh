#!/bin/sh
# Regenerate the example recordings shipped in features/examples/ (see its __init__.py).
set -e
D=features/examples
for m in 0 0.5; do
  name=$([ "$m" = 0 ] && echo aligned || echo misaligned)
  for ext in csv h5; do
    rotordiag simulate --speed-rpm 1800 --misalignment $m --unbalance 0.05 --record-revs 40 \
      --probe-sample-rate-hz 2560 --snr-db 40 --runout-um 1 --seed 1 --probes-out $D/$name.$ext > /dev/null
  done
done
rotordiag simulate --speed-rpm 1800 --misalignment 0.5 --unbalance 0.05 --record-revs 40 \
  --probe-sample-rate-hz 2560 --snr-db 40 --runout-um 1 --seed 1 --probes-out $D/misaligned_2560hz.npy > /dev/null
echo '{"sample_rate_hz": 2560}' > $D/misaligned_2560hz.json
rm -f $D/misaligned.uff
rotordiag simulate --speed-rpm 1800 --misalignment 0.5 --unbalance 0.05 --record-revs 40 \
  --probe-sample-rate-hz 2560 --snr-db 40 --runout-um 1 --seed 1 --probes-out $D/misaligned.uff > /dev/null
