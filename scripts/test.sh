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
[ -x .venv/bin/python ] || { echo "== python -m venv .venv"; "$PY" -m venv .venv; }
echo "== pip install -e '.[dev,distributed,baselines]' into .venv (numba, torch, ray, stable-baselines3, pytest, ...)"
.venv/bin/python -m pip install -q --disable-pip-version-check -e '.[dev,distributed,baselines]'
if [ $# -gt 0 ]; then  # tests or options given: one pytest run of them
  exec .venv/bin/python -m pytest -n 2 --dist loadgroup "$@"
fi

# the whole suite part by part (about 12 minutes on 2 cores), each part's outcome and time, then a summary
summary=()
status=0
for part in tests/foundation tests/arena tests/learning tests/experiments tests/engine; do
  echo "== $part"
  start=$SECONDS
  if .venv/bin/python -m pytest -n 2 --dist loadgroup -q -rfEs "$part"; then outcome=passed; else outcome=FAILED; status=1; fi
  summary+=("$part: $outcome in $((SECONDS - start)) s")
done
echo "== summary"
printf '  %s\n' "${summary[@]}"
exit $status
