#!/usr/bin/env bash
# The live view and a recording seen in a real Foxglove-compatible app in a real browser:
# Lichtblick's web app, built from its own source, served on this host and driven in
# headless Chromium (bench/scripts/lichtblick/view.mjs). It connects to a running
# `rig run --live --timing realtime --speed 10`, imports docs/live-layout.json and takes
# screenshots seconds apart; then it opens a finished run's run.mcap with the same layout.
# It exits 1 if it did not see the system drawn, a value in every plot or the 3D panel move
# (live), or, on the recording, every panel's topics, a value in every plot and the system.
#
#   bench/scripts/lichtblick.sh --lichtblick SRC [--out DIR]   # builds the app (minutes)
#   bench/scripts/lichtblick.sh --app DIR [--out DIR]          # a built web app
#   bench/scripts/lichtblick.sh [--out DIR]                    # the app built before
#
# SRC: a checkout of Lichtblick's repository (Lichtblick-Suite/lichtblick); it is copied
# and built under target/lichtblick/ with its own yarn (npm's @yarnpkg/cli-dist, the
# version its package.json names) and its `web:build:prod` script, everything from the
# npm registry. RIG: the rig to run (default: built here with `--features live`).
# Writes DIR/live-1.png, DIR/live-2.png, DIR/recording.png and DIR/checks.json (default
# docs/results/live). Not part of CI: the build takes minutes, the browser a core.
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
work="$repo/target/lichtblick"
out="$repo/docs/results/live"
src=""
app=""
while [ $# -gt 0 ]; do
  case "$1" in
    --lichtblick) src="$(cd "$2" && pwd)"; shift 2 ;;
    --app) app="$(cd "$2" && pwd)"; shift 2 ;;
    --out) mkdir -p "$2"; out="$(cd "$2" && pwd)"; shift 2 ;;
    -h|--help) sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "lichtblick.sh: unknown argument $1 (--help)" >&2; exit 2 ;;
  esac
done

# What it needs, checked before it starts: one line naming what is missing and how to get it.
missing() { echo "lichtblick.sh: missing: $*" >&2; exit 2; }
command -v node >/dev/null || missing "Node.js 20 or newer (apt-get install nodejs npm)"
command -v npm >/dev/null || missing "npm (apt-get install npm)"
node -e 'process.exit(Number(process.versions.node.split(".")[0]) >= 20 ? 0 : 1)' ||
  missing "Node.js 20 or newer, not $(node --version) (Lichtblick's build needs it)"
chromium="${CHROMIUM:-/usr/bin/chromium}"
[ -x "$chromium" ] || missing "Chromium at $chromium (apt-get install chromium, or set CHROMIUM)"
if [ -z "${RIG:-}" ]; then
  command -v cargo >/dev/null || missing "cargo, to build rig (or set RIG to a rig built with --features live)"
fi
if [ -z "$app" ] && [ -z "$src" ]; then
  app="$work/app"
  [ -f "$app/index.html" ] || missing "Lichtblick: --lichtblick SRC (a checkout of Lichtblick-Suite/lichtblick, built here) or --app DIR (its built web app)"
fi

pids=()
cleanup() {
  local status=$?
  for p in "${pids[@]}"; do
    kill -TERM "$p" 2>/dev/null || true
  done
  for p in "${pids[@]}"; do
    wait "$p" 2>/dev/null || true
  done
  exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# Lichtblick's web app, built from its source unless given.
if [ -n "$src" ]; then
  app="$work/app"
  "$repo/bench/scripts/lichtblick/build.sh" "$src" "$work" >&2
fi
version="$(cat "$app/../version" 2>/dev/null || echo "(version unknown)")"

# The browser's driver, from the lock file.
(cd "$repo/bench/scripts/lichtblick" && [ -d node_modules/puppeteer-core ] ||
  PUPPETEER_SKIP_DOWNLOAD=1 npm ci --no-audit --no-fund --silent)

if [ -z "${RIG:-}" ]; then
  echo "building rig with the live view (cargo build --release -p rig --features live)" >&2
  (cd "$repo" && cargo build --release -p rig --features live --quiet)
  RIG="$repo/target/release/rig"
fi

files="$work/files"
rm -rf "$files" "$work/recorded" "$work/live-run"
mkdir -p "$files"
cp "$repo/docs/live-layout.json" "$files/"

# A finished run (lockstep, the default): its recording.
echo "a recorded run: rig run --trials 60 --out $work/recorded" >&2
"$RIG" run --trials 60 --quiet --out "$work/recorded"
cp "$work/recorded/run.mcap" "$files/run.mcap"

# The live run, viewed while it goes on: the loop keeps its period with the browser beside
# it only when its gaps are learnt across (the browser draws on the same two cores).
port="$(node -e 'const s = require("net").createServer().listen(0, "127.0.0.1", () => { console.log(s.address().port); s.close(); })')"
echo "a live run: rig run --live 127.0.0.1:$port --timing realtime --speed 10 --gaps learn" >&2
"$RIG" run --live "127.0.0.1:$port" --timing realtime --speed 10 --gaps learn \
  --trials 3000 --quiet --out "$work/live-run" &
pids+=($!)

profile="$(mktemp -d)"
status=0
node "$repo/bench/scripts/lichtblick/view.mjs" --app "$app" --files "$files" \
  --live "ws://127.0.0.1:$port" --mcap run.mcap --layout live-layout.json \
  --out "$out" --profile "$profile" --chromium "$chromium" &
pids+=($!)
wait $! || status=$?
rm -rf "$profile"
echo "Lichtblick $version, $("$chromium" --version 2>/dev/null | head -1), rig at $(git -C "$repo" rev-parse --short HEAD)" >&2
echo "screenshots: $out" >&2
exit "$status"
