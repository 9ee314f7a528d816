#!/usr/bin/env bash
# Installs everything the renderer needs on a fresh Debian 12 (bookworm) as root:
# the Vulkan loader, Mesa 25 lavapipe from bookworm-backports (stock Mesa 22.3 has
# no ray tracing), the Khronos validation layer, Xvfb for the window test, the
# C++ toolchain shaderc's from-source build uses (see README "Shader compiler")
# and RenderDoc 1.24 with its Python module (tests/cli/renderdoc.rs captures a frame).
# Idempotent: a second run only checks.
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive

# The mirror this machine already uses for bookworm (deb822 .sources or one-line
# sources.list), so backports come from the same place (a local mirror or proxy).
# The script names no host itself: with no bookworm source it fails, saying so.
debian_mirror() {
  local uri files
  shopt -s nullglob
  files=("$APT_ETC"/sources.list.d/*.sources)
  uri=""
  [ "${#files[@]}" -gt 0 ] && uri=$(awk '
    /^[[:space:]]*#/ { next }
    /^[[:space:]]*$/ { if (uris != "" && suites ~ /(^| )bookworm( |$)/) { print uris; exit } uris=""; suites=""; next }
    /^URIs:/ { uris=$2 }
    /^Suites:/ { $1=""; suites=$0 " " }
    END { if (uris != "" && suites ~ /(^| )bookworm( |$)/) print uris }
  ' "${files[@]}" | head -n1 || true)
  if [ -z "$uri" ]; then
    files=("$APT_ETC"/sources.list "$APT_ETC"/sources.list.d/*.list)
    uri=$(cat "${files[@]}" 2>/dev/null |
      awk '$1 == "deb" { i = 2; if ($2 ~ /^\[/) { while (i <= NF && $i !~ /\]$/) i++; i++ }
                         if ($(i+1) == "bookworm") { print $i; exit } }' || true)
  fi
  shopt -u nullglob
  if [ -z "$uri" ]; then
    echo "setup: no bookworm apt source configured in $APT_ETC/sources.list or $APT_ETC/sources.list.d/:" \
      "add one (e.g. a deb822 .sources file with 'Suites: bookworm') and run this again" >&2
    return 1
  fi
  echo "$uri"
}

# True when some source already provides bookworm-backports.
backports_configured() {
  grep -rqsE '(^|[[:space:]])bookworm-backports([[:space:]]|$)' "$APT_ETC"/sources.list "$APT_ETC"/sources.list.d/
}

pkgs=(libvulkan1 vulkan-tools vulkan-validationlayers cmake ninja-build python3 g++ git
      xvfb xauth libx11-6 libx11-xcb1 libxcursor1 libxrandr2 libxi6 libxkbcommon-x11-0
      fonts-dejavu-core renderdoccmd python3-renderdoc)

# APT_ETC: only for tests of the mirror detection (tests/cli/setup_script.rs).
APT_ETC=${APT_ETC:-/etc/apt}
if [ "${1:-}" = "--print-mirror" ]; then
  debian_mirror
  exit
fi

need_install=0
for p in "${pkgs[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || need_install=1
done
lvp_ok=0
if dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null | grep -q '^25\.'; then
  lvp_ok=1
fi

if [ "$need_install" = 1 ] || [ "$lvp_ok" = 0 ]; then
  if [ ! -f /etc/apt/sources.list.d/bookworm-backports.sources ] && ! backports_configured; then
    mirror=$(debian_mirror) || exit 1
    echo "setup: adding bookworm-backports from $mirror"
    cat > /etc/apt/sources.list.d/bookworm-backports.sources <<SRC
Types: deb
URIs: $mirror
Suites: bookworm-backports
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
SRC
  fi
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${pkgs[@]}" >/dev/null
  apt-get install -y -qq --no-install-recommends -t bookworm-backports mesa-vulkan-drivers >/dev/null
fi

# The Rust toolchain (>= 1.88) comes from rustup, not apt: Debian 12's rustc is too old.
if ! command -v cargo >/dev/null 2>&1 && [ ! -x "$HOME/.cargo/bin/cargo" ]; then
  echo "setup: cargo not found: install Rust >= 1.88 with rustup first" >&2
  exit 1
fi
echo "setup: mesa-vulkan-drivers $(dpkg-query -W -f='${Version}' mesa-vulkan-drivers)"
