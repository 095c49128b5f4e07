#!/usr/bin/env bash
# Builds Lichtblick's web app from a checkout of its repository, everything from the npm
# registry: its yarn (@yarnpkg/cli-dist, the version its package.json names), its packages
# (yarn.lock) and its `web:build:prod` script; ELECTRON_SKIP_BINARY_DOWNLOAD and the
# like keep install scripts from downloading anything else.
#
#   bench/scripts/lichtblick/build.sh SRC WORK
#
# SRC is copied to WORK/src (SRC itself is left as it is) and the app written to WORK/app;
# a build of the same source (its package.json and yarn.lock) is reused. A checkout
# without its Git LFS files has text pointers in their place: the yarn plugins (not
# needed to install or build: left out), the fonts (the same typefaces from npm:
# @fontsource/inter, @ibm/plex-mono) and pictures (left as they are: panel thumbnails,
# icons). Takes 5 to 25 minutes on 2 cores; needs about 8 GB of memory.
set -euo pipefail
src="$1"
work="$2"
mkdir -p "$work"
stamp="$(cat "$src/package.json" "$src/yarn.lock" | sha256sum | cut -c1-16)"
if [ -f "$work/app/index.html" ] && [ "$(cat "$work/stamp" 2>/dev/null)" = "$stamp" ]; then
  echo "Lichtblick: reusing the app built from this source in $work/app"
  exit 0
fi
rm -rf "$work/src" "$work/app" "$work/stamp"
mkdir -p "$work/src"
tar -C "$src" --exclude=./node_modules --exclude=./.git --exclude=./web/.webpack -cf - . |
  tar -C "$work/src" -xf -
cd "$work/src"
version="$(node -p 'require("./package.json").version')"
yarn_version="$(node -p 'require("./package.json").packageManager.replace(/^yarn@/, "")')"
echo "Lichtblick $version: its yarn $yarn_version from npm"
npm install --prefix "$work/tools" --no-save --no-audit --no-fund --silent \
  "@yarnpkg/cli-dist@$yarn_version" @fontsource/inter@5.3.0 @ibm/plex-mono@2.5.0
modules="$work/tools/node_modules"

is_pointer() { head -c 40 "$1" | grep -q '^version https://git-lfs'; }
# The yarn plugins, if only pointers: left out (yarnPath, the corepack wrapper, too).
if is_pointer .yarn/plugins/@yarnpkg/plugin-workspace-tools.cjs 2>/dev/null; then
  echo "Lichtblick: its yarn plugins are Git LFS pointers: installing and building without them"
  node -e '
    const fs = require("fs");
    const rc = fs.readFileSync(".yarnrc.yml", "utf8");
    fs.writeFileSync(".yarnrc.yml", rc.replace(/^plugins:\n(  .*\n)+/m, ""));'
fi
# The fonts, if only pointers: the same typefaces from npm.
fonts=packages/suite-base/src/styles/assets
font() { # NAME FILE
  if is_pointer "$fonts/$1.woff2"; then cp "$modules/$2" "$fonts/$1.woff2"; fi
}
font Inter-Regular @fontsource/inter/files/inter-latin-400-normal.woff2
font Inter-Italic @fontsource/inter/files/inter-latin-400-italic.woff2
font Inter-Medium @fontsource/inter/files/inter-latin-500-normal.woff2
font Inter-MediumItalic @fontsource/inter/files/inter-latin-500-italic.woff2
font Inter-SemiBold @fontsource/inter/files/inter-latin-600-normal.woff2
font Inter-SemiBoldItalic @fontsource/inter/files/inter-latin-600-italic.woff2
font PlexMono @ibm/plex-mono/fonts/complete/woff2/IBMPlexMono-Regular.woff2
font PlexMono-Italic @ibm/plex-mono/fonts/complete/woff2/IBMPlexMono-Italic.woff2
font PlexMono-Bold @ibm/plex-mono/fonts/complete/woff2/IBMPlexMono-Bold.woff2
font PlexMono-BoldItalic @ibm/plex-mono/fonts/complete/woff2/IBMPlexMono-BoldItalic.woff2

export YARN_IGNORE_PATH=1 YARN_ENABLE_TELEMETRY=0 YARN_ENABLE_GLOBAL_CACHE=0
registry="$(npm config get registry)"
export YARN_NPM_REGISTRY_SERVER="${registry%/}"
export ELECTRON_SKIP_BINARY_DOWNLOAD=1 PUPPETEER_SKIP_DOWNLOAD=1
export PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 CYPRESS_INSTALL_BINARY=0
export NODE_OPTIONS=--max-old-space-size=8192
yarn=(node "$modules/@yarnpkg/cli-dist/bin/yarn.js")
echo "Lichtblick: yarn install (log: $work/install.log)"
nice "${yarn[@]}" install > "$work/install.log" 2>&1 || { tail -20 "$work/install.log"; exit 1; }
echo "Lichtblick: yarn web:build:prod (log: $work/build.log)"
nice "${yarn[@]}" web:build:prod > "$work/build.log" 2>&1 || { tail -20 "$work/build.log"; exit 1; }
mv web/.webpack "$work/app"
echo "$version" > "$work/version"
echo "$stamp" > "$work/stamp"
echo "Lichtblick $version: built in $work/app"
