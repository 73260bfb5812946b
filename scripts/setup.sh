#!/usr/bin/env bash
# Checks (and on Debian/Ubuntu installs) what building and running ppm-vk needs: a Rust toolchain, a C++
# toolchain, the Vulkan loader, a Vulkan driver (lavapipe when there is no GPU), shaderc/glslang to compile
# the kernels, the validation layer the tests run under, the X11/Wayland libraries `ppm-vk view` loads
# when it opens a window, and Xvfb for the viewer's headless tests. Sourced by scripts/ppm-vk and scripts/test;
# run it alone to check a machine. Exits non-zero with the exact command to run where it cannot fix things.
set -euo pipefail

say() { printf 'setup: %s\n' "$*" >&2; }
has_vulkan_driver() { compgen -G '/usr/share/vulkan/icd.d/*.json' >/dev/null || compgen -G '/etc/vulkan/icd.d/*.json' >/dev/null; }

# Debian package -> what it provides.
DEBIAN_PACKAGES=(
  "libvulkan1:the Vulkan loader"
  "libvulkan-dev:Vulkan headers"
  "mesa-vulkan-drivers:lavapipe, the CPU Vulkan driver (and Mesa's GPU drivers)"
  "vulkan-validationlayers:the validation layer the tests run under"
  "libshaderc-dev:shaderc, the GLSL compiler the kernels are built with"
  "glslang-dev:glslang's static libraries shaderc links against"
  "spirv-tools:SPIRV-Tools' static libraries"
  "g++:a C++ toolchain (shaderc is C++)"
  "pkg-config:library lookup"
  "libx11-6:X11 client library (ppm-vk view's window, loaded at run time)"
  "libx11-xcb1:X11/XCB glue (ppm-vk view)"
  "libxcursor1:X11 cursors (ppm-vk view)"
  "libxrandr2:X11 monitor sizes (ppm-vk view)"
  "libxi6:X11 input devices (ppm-vk view)"
  "libxkbcommon-x11-0:keyboard layouts on X11 (ppm-vk view)"
  "libwayland-client0:Wayland client library (ppm-vk view on Wayland)"
  "xvfb:a headless X server the viewer's tests open their windows on"
  "python3:the layering check of scripts/test (scripts/import-cycles.py)"
  "python3-venv:the Python package's environment (scripts/python-install; pip fetches maturin, numpy, pytest)"
)

if ! command -v cargo >/dev/null 2>&1; then
  if [ -x "$HOME/.cargo/bin/cargo" ]; then
    export PATH="$HOME/.cargo/bin:$PATH"
  else
    say "no Rust toolchain (cargo) found. Install one with rustup:"
    say "  curl --proto '=https' --tlsv1.2 -sSf https://sh.rustup.rs | sh -s -- -y && . \"\$HOME/.cargo/env\""
    exit 1
  fi
fi

if command -v dpkg-query >/dev/null 2>&1; then
  missing=()
  for entry in "${DEBIAN_PACKAGES[@]}"; do
    pkg=${entry%%:*}
    if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
      missing+=("$pkg")
    fi
  done
  if [ ${#missing[@]} -gt 0 ]; then
    say "installing: ${missing[*]}"
    if [ "$(id -u)" -eq 0 ]; then
      SUDO=""
    elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
      SUDO="sudo"
    else
      say "cannot install packages without root. Run:"
      say "  sudo apt-get update && sudo apt-get install -y ${missing[*]}"
      exit 1
    fi
    export DEBIAN_FRONTEND=noninteractive
    if ! { $SUDO apt-get update -qq && $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null; }; then
      say "apt-get could not install ${missing[*]}; install them by hand and rerun"
      exit 1
    fi
  fi
else
  # Not Debian: check for the files themselves and say what to do.
  ok=1
  ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1' || { say "no Vulkan loader (libvulkan.so.1): install your distribution's vulkan-loader"; ok=0; }
  has_vulkan_driver || { say "no Vulkan driver: install Mesa's Vulkan drivers (lavapipe) or your GPU's"; ok=0; }
  say "not a Debian system: shaderc is linked through the override in .cargo/config.toml, written for Debian's"
  say "static libraries; elsewhere remove that block and set SHADERC_LIB_DIR (see .cargo/config.toml)"
  [ $ok -eq 1 ] || exit 1
fi

# A driver must actually be there: the loader alone renders nothing.
if ! has_vulkan_driver; then
  say "no Vulkan driver manifest in /usr/share/vulkan/icd.d: install mesa-vulkan-drivers"
  exit 1
fi
# lavapipe and the loader look for a runtime directory; give them one where the session has none.
if [ -z "${XDG_RUNTIME_DIR:-}" ] || [ ! -d "${XDG_RUNTIME_DIR}" ]; then
  export XDG_RUNTIME_DIR="${TMPDIR:-/tmp}"
fi
