#!/usr/bin/env bash
# Run every benchmark in turn against this checkout (not whatever hybridpd is installed).
set -euo pipefail; cd "$(dirname "$0")/.."; for f in benchmarks/bench_*.py; do echo "== $f"; PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}" python "$f"; done
