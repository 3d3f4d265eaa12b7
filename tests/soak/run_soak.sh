#!/usr/bin/env bash
# The soak by hand (doc/reliability.md): 10,000 real scans (SENA, lap after lap, each lap moved by
# a small random offset) into one map, a checkpoint every thousand. From the repository root,
# after a Release build: bash tests/soak/run_soak.sh [build-dir]
set -euo pipefail
build="${1:-build}"
exec "$build/tests/soak/rtog_soak" --scans 10000 --every 1000 --max-growth 0.10
