#!/usr/bin/env bash
# Checks a `haze compare --report DIR` page in headless Chromium and takes a screenshot of it.
#
#   scripts/report-screenshot.sh REPORT_DIR [OUT.png] [WIDTH]
#
# 1. Loads REPORT_DIR/index.html and reads back the `data-images` mark the page sets on load
#    (`ok`, or the list of images that failed to load); exits 1 unless it is `ok`.
# 2. Writes a full-page screenshot (default REPORT_DIR/screenshot.png), to look at.
# Needs Chromium (Debian: `apt-get install chromium`); CHROMIUM=... selects another binary.
set -euo pipefail
dir=${1:?usage: scripts/report-screenshot.sh REPORT_DIR [OUT.png] [WIDTH]}
out=${2:-$dir/screenshot.png}
width=${3:-1400}
page=$(realpath "$dir/index.html")
chromium=${CHROMIUM:-$(command -v chromium || command -v chromium-browser || command -v google-chrome || true)}
if [ -z "$chromium" ]; then
  echo "error: no Chromium found (apt-get install chromium, or set CHROMIUM=/path/to/chrome)" >&2
  exit 2
fi
profile=$(mktemp -d)
trap 'rm -rf "$profile"' EXIT
# The flags keep Chromium off the network (this machine has none) and out of the user's profile.
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking
  --disable-component-update --disable-sync --hide-scrollbars "--user-data-dir=$profile"
  --virtual-time-budget=10000)
dom=$("$chromium" "${flags[@]}" --dump-dom "file://$page" 2>/dev/null)
mark=$(printf '%s' "$dom" | grep -o 'data-images="[^"]*"' | head -1 || true)
if [ "$mark" != 'data-images="ok"' ]; then
  echo "error: $page did not load completely in Chromium: ${mark:-no data-images mark (script did not run)}" >&2
  exit 1
fi
# The page height: the screenshot is of a fixed window, so make it tall enough for the whole page.
height=${HEIGHT:-2400}
"$chromium" "${flags[@]}" "--window-size=$width,$height" "--screenshot=$(realpath -m "$out")" "file://$page" 2>/dev/null
echo "all images loaded; screenshot: $out (${width}x${height})" >&2
