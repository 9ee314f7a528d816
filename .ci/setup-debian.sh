#!/usr/bin/env bash
# Installs everything the renderer needs on a fresh Debian 12 (bookworm) as root:
# the Vulkan loader, Mesa 25 lavapipe from bookworm-backports (stock Mesa 22.3 has
# no ray tracing), the Khronos validation layer, Xvfb for the window test, and the
# C++ toolchain shaderc's from-source build uses (see README "Shader compiler").
# Idempotent: a second run only checks.
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive

pkgs=(libvulkan1 vulkan-tools vulkan-validationlayers cmake ninja-build python3 g++ git
      xvfb xauth libx11-6 libx11-xcb1 libxcursor1 libxrandr2 libxi6 libxkbcommon-x11-0)

need_install=0
for p in "${pkgs[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || need_install=1
done
lvp_ok=0
if dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null | grep -q '^25\.'; then
  lvp_ok=1
fi

if [ "$need_install" = 1 ] || [ "$lvp_ok" = 0 ]; then
  if [ ! -f /etc/apt/sources.list.d/bookworm-backports.sources ]; then
    cat > /etc/apt/sources.list.d/bookworm-backports.sources <<'SRC'
Types: deb
URIs: http://deb.debian.org/debian
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
