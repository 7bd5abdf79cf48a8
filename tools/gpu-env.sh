# Sourced by tools/gpu-check and tools/bench-gpu on the device machine.
#
# gpu_env DIR: unpacks the Vulkan loader and validation layer packages in DIR (*.deb,
# downloaded by `tools/gpu-check prepare`) into DIR/root, not /, and points the loader
# there: the loader by LD_LIBRARY_PATH, the layer's manifest by VK_ADD_LAYER_PATH (its
# library by name, through the same path), the NVIDIA driver's manifest by
# VK_DRIVER_FILES where the system does not install one.
gpu_env() {
  local prefix=$1/root f
  rm -rf "$prefix" && mkdir -p "$prefix"
  for f in "$1"/*.deb; do dpkg -x "$f" "$prefix"; done
  export LD_LIBRARY_PATH=$prefix/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
  export VK_ADD_LAYER_PATH=$prefix/usr/share/vulkan/explicit_layer.d
  if ! ls /usr/share/vulkan/icd.d/nvidia* /etc/vulkan/icd.d/nvidia* >/dev/null 2>&1; then
    export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
  fi
}
