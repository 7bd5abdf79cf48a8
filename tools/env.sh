# Sourced by tools/run and tools/test: makes a fresh Debian 12 machine ready.
# - installs the Debian packages Speculum needs, when missing (as root or via sudo);
# - on Debian 12 with no GPU, takes lavapipe from Mesa 25 in bookworm-backports
#   (2.5x faster frames than bookworm's Mesa 22.3.6, same images), adding the
#   backports source when missing; where backports cannot be reached it keeps the
#   installed driver and says so in one line (SPECULUM_MESA_BACKPORTS=0 skips this);
# - finds rustup's cargo;
# - pins lavapipe (Mesa's CPU Vulkan driver) when no GPU driver is present.
set -euo pipefail

SPECULUM_PACKAGES=(mesa-vulkan-drivers libvulkan1 libvulkan-dev vulkan-validationlayers
  libshaderc-dev glslang-dev glslang-tools spirv-tools xvfb xauth
  libembree-dev)

# Cargo features tools/run and tools/test build with (one build serves both): the
# Embree 3 anchor of `bench lbvh` (libembree-dev, above).
SPECULUM_FEATURES=(--features embree)

speculum_has_gpu() {
  [ -e /dev/nvidia0 ] || ls /dev/dri/renderD* >/dev/null 2>&1
}

speculum_missing_packages() {
  local p
  for p in "${SPECULUM_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || echo "$p"
  done
}

# True when this machine should take Mesa from bookworm-backports: Debian 12, no GPU,
# not opted out, and the installed lavapipe (if any) older than Mesa 25.
speculum_wants_backports_mesa() {
  [ "${SPECULUM_MESA_BACKPORTS:-1}" != 0 ] || return 1
  grep -qx 'VERSION_CODENAME=bookworm' /etc/os-release 2>/dev/null || return 1
  speculum_has_gpu && return 1
  local v
  v=$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || true)
  [ -z "$v" ] && return 0
  dpkg --compare-versions "$v" lt 25
}

# Prints field $1 (URIs, Signed-By) of the first deb822 stanza of type deb whose
# Suites include bookworm (nothing when that stanza lacks it).
speculum_bookworm_field() {
  # shellcheck disable=SC2046 # a list of files
  awk -v field="$1" 'BEGIN{RS=""} /Suites:[^\n]*bookworm( |\n|$)/ && /Types:[^\n]*deb( |\n|$)/ {
      if (match($0, field ": *[^ \n]+")) { s = substr($0, RSTART, RLENGTH); sub(field ": *", "", s); print s }
      exit }' $(ls /etc/apt/sources.list.d/*.sources 2>/dev/null) /dev/null
}

# Adds a bookworm-backports source with the URI and keyring of the machine's own
# bookworm source (deb822 or one-line format), when no source names backports yet.
speculum_add_backports_source() {
  local sudo=$1 files uri keyring=""
  files=$(ls /etc/apt/sources.list /etc/apt/sources.list.d/*.list /etc/apt/sources.list.d/*.sources 2>/dev/null || true)
  [ -n "$files" ] || return 1
  # shellcheck disable=SC2086 # a list of files
  grep -qs 'bookworm-backports' $files && return 0
  # deb822: the first deb stanza whose Suites include bookworm; its keyring too.
  uri=$(speculum_bookworm_field URIs)
  if [ -n "$uri" ]; then
    keyring=$(speculum_bookworm_field Signed-By)
  else
    # One-line format: deb [options] URI bookworm main ...
    # shellcheck disable=SC2086
    uri=$(awk '$1 == "deb" { for (i = 2; i <= NF; i++) if ($i ~ /^\[/) { while ($i !~ /\]$/) i++; continue } else { if ($(i+1) == "bookworm") { print $i; exit } break } }' $files /dev/null)
  fi
  [ -n "$uri" ] || return 1
  {
    echo "Types: deb"
    echo "URIs: $uri"
    echo "Suites: bookworm-backports"
    echo "Components: main"
    [ -n "$keyring" ] && echo "Signed-By: $keyring"
  } | $sudo tee /etc/apt/sources.list.d/speculum-bookworm-backports.sources >/dev/null
  echo "tools: added bookworm-backports ($uri) for Mesa 25" >&2
}

speculum_install_packages() {
  local missing backports=0 sudo=""
  missing=$(speculum_missing_packages)
  speculum_wants_backports_mesa && backports=1
  [ -z "$missing" ] && [ $backports = 0 ] && return 0
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "tools: need root or sudo to install" $missing >&2; exit 1; }
    sudo="sudo"
  fi
  if [ $backports = 1 ] && ! speculum_add_backports_source "$sudo"; then
    backports=0
    echo "tools: no bookworm source to derive bookworm-backports from; keeping the installed Mesa" >&2
  fi
  $sudo apt-get update -qq || echo "tools: apt-get update reported errors (continuing)" >&2
  if [ $backports = 1 ]; then
    echo "tools: installing mesa-vulkan-drivers from bookworm-backports (Mesa 25 lavapipe)" >&2
    if ! DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq -t bookworm-backports \
        mesa-vulkan-drivers >/dev/null; then
      echo "tools: bookworm-backports unreachable; using mesa-vulkan-drivers from bookworm" \
        "($(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || echo 'to be installed'))" >&2
    fi
  fi
  missing=$(speculum_missing_packages)
  [ -z "$missing" ] && return 0
  # shellcheck disable=SC2086 # a list of packages
  echo "tools: installing" $missing >&2
  # shellcheck disable=SC2086
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq $missing >/dev/null
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
  speculum_has_gpu && return 0
  local icd
  icd=$(ls /usr/share/vulkan/icd.d/lvp_icd*.json 2>/dev/null | head -n 1 || true)
  if [ -n "$icd" ]; then
    export VK_ICD_FILENAMES="$icd"
    echo "tools: no GPU found, using lavapipe $(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null) ($icd)" >&2
  fi
}

cd "$(dirname "${BASH_SOURCE[0]}")/.."
speculum_install_packages
speculum_find_cargo
speculum_pin_driver
