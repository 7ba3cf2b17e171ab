#!/usr/bin/env bash
# The whole test suite on a fresh machine: Python deps in .venv, and (as root) the real Robocode engine, Chromium
# and Xvfb from Debian's packages for the engine, replay-player and battle-window tests (those tests skip when absent).
set -euo pipefail
cd "$(dirname "$0")/.."

if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
  need=()
  [ -f /usr/share/java/robocode.jar ] || need+=(robocode)
  command -v chromium >/dev/null || need+=(chromium)
  command -v Xvfb >/dev/null || need+=(xvfb)
  [ -d /usr/share/fonts/truetype/dejavu ] || need+=(fonts-dejavu-core)  # the battle window's text
  if [ ${#need[@]} -gt 0 ]; then
    echo "== apt-get install ${need[*]}"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${need[@]}" default-jdk-headless >/dev/null
  fi
fi

PY=${PYTHON:-python3}
[ -x .venv/bin/python ] || "$PY" -m venv .venv
.venv/bin/python -m pip install -q --disable-pip-version-check -e '.[dev,distributed,baselines]'
exec .venv/bin/python -m pytest -n 2 --dist loadgroup "$@"
