#!/usr/bin/env bash
# The Python package on the device machine: the abi3 wheel built here, CuPy raw kernels and
# PyTorch on CUDA judged through it (crates/python/device/gpu_clients.py), and the 1024x1024
# judging benchmark against `fragsim compare` (crates/python/bench/judge_1024.py).
#
# Carried in .device/python/ (git-ignored in the tree the device copies): fragsim-*.whl
# (`maturin build --release -o .device/python` in crates/python), the fragsim binary
# (target/release/fragsim), gpu_clients.py and judge_1024.py. Run from the tree's root:
#   bash .device/python/python-gpu.sh        (outputs in $OUT)
set -euo pipefail
here=.device/python
out=${OUT:-/tmp}
python3 -m pip install -q --no-deps --no-index --target /tmp/fragsim-py "$here"/fragsim-*.whl
export PYTHONPATH=/tmp/fragsim-py
python3 -c "import fragsim; print('fragsim', fragsim.__version__, 'from', fragsim.__file__)"
python3 "$here/gpu_clients.py" bunny 1024 1024 2>&1 | tee "$out/gpu-clients.log"
python3 "$here/judge_1024.py" "$here/fragsim" 5 2>&1 | tee "$out/judge-1024.log"
