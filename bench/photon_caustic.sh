#!/bin/sh
# The photon-mapping proof on the TNCG15 room (eye 1, 128x128, vs tests/data/refs/hexroom-eye1.exr):
# caustic-region RMSE of photon and sppm against path at equal time, and sppm's whole-image
# RMSE per iteration. Writes target/photon-caustic.md (the tables) and
# docs/photon-sppm-convergence.svg (the plot). About half a minute on two cores (photon 8.7 s, sppm 7.0 s, path
# to the same times); last run: caustic RMSE ratio to path 0.47 (photon), 0.38 (sppm).
set -e
cd "$(dirname "$0")/.."
cargo test --test photon caustic_rmse_at_equal_time -- --ignored --nocapture || true
cat target/photon-caustic.md
