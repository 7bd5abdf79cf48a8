# Sourced by tools/run and tools/test: makes a fresh Debian 12 machine ready.
# - installs the Debian packages Speculum needs, when missing (as root or via sudo);
# - finds rustup's cargo;
# - pins lavapipe (Mesa's CPU Vulkan driver) when no GPU driver is present.
set -euo pipefail

SPECULUM_PACKAGES=(mesa-vulkan-drivers libvulkan1 libvulkan-dev vulkan-validationlayers
  libshaderc-dev glslang-dev glslang-tools spirv-tools xvfb xauth fonts-dejavu-core)

speculum_install_packages() {
  local missing=()
  for p in "${SPECULUM_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "tools: installing ${missing[*]}" >&2
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "tools: need root or sudo to install ${missing[*]}" >&2; exit 1; }
    sudo="sudo"
  fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >/dev/null
}

speculum_find_cargo() {
  if ! command -v cargo >/dev/null; then
    [ -f "$HOME/.cargo/env" ] && . "$HOME/.cargo/env"
  fi
  command -v cargo >/dev/null || { echo "tools: cargo not found; install Rust with rustup" >&2; exit 1; }
}

speculum_pin_driver() {
  # Respect a driver the caller chose.
  [ -n "${VK_ICD_FILENAMES:-}" ] || [ -n "${VK_DRIVER_FILES:-}" ] && return 0
  # A GPU with a driver present: let the loader find it (Speculum prefers it).
  if [ -e /dev/nvidia0 ] || ls /dev/dri/renderD* >/dev/null 2>&1; then
    return 0
  fi
  local icd
  icd=$(ls /usr/share/vulkan/icd.d/lvp_icd.*.json 2>/dev/null | head -n 1 || true)
  if [ -n "$icd" ]; then
    export VK_ICD_FILENAMES="$icd"
    echo "tools: no GPU found, using lavapipe ($icd)" >&2
  fi
}

cd "$(dirname "${BASH_SOURCE[0]}")/.."
speculum_install_packages
speculum_find_cargo
speculum_pin_driver
