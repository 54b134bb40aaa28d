#!/usr/bin/env bash
# Renders the bundled VST3 in pedalboard (PyPI) and checks it: see render_vst3.py.
# Needs target/bundled/javari.vst3 (cargo xtask bundle javari --release) and python3 with venv.
set -euo pipefail
cd "$(dirname "$0")/../.."
venv=target/pedalboard-venv
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/pip" install --quiet --disable-pip-version-check pedalboard==0.9.26 numpy==2.4.6
"$venv/bin/python" tests/pedalboard/render_vst3.py target/bundled/javari.vst3
