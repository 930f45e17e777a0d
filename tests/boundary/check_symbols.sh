#!/usr/bin/env bash
# Fails when libhmsm defines a symbol an engine could collide with.
# - Static library: no vk*/volk* symbol at all, and every strong global definition (nm types
#   T, D, B, R) is hmsm's own (namespace hmsm or the C ABI's hmsm_*). Weak definitions (W, V, u)
#   are inline functions and template instantiations, which the linker merges by name.
# - Neither library defines a visible CUDA runtime symbol (the runtime is folded in privately).
# - Shared library: every exported definition (nm -D) is hmsm's own public API (no detail::,
#   Simulation::Impl or Simulation::Access member).
# Usage: check_symbols.sh libhmsm.a libhmsm.so
set -euo pipefail
static_lib="$1"; shared_lib="$2"
status=0

is_own() { grep -Ev '^(_ZN4hmsm|_ZNK4hmsm|_ZZN4hmsm|_ZZNK4hmsm|_ZTVN4hmsm|_ZTIN4hmsm|_ZTSN4hmsm|hmsm_)'; }

vk=$(nm -g --defined-only "$static_lib" 2>/dev/null | awk 'NF == 3 {print $3}' | grep -E '^_?(vk|volk)' || true)
if [[ -n "$vk" ]]; then
    echo "$static_lib defines Vulkan/volk symbols:"; echo "$vk" | head -20; status=1
fi
# The CUDA runtime folded into a CUDA build (cmake/fold_cudart.sh) stays private: no definition
# of it, weak ones included, is global in either library.
cudart=$( (nm -g --defined-only "$static_lib" 2>/dev/null; nm -D --defined-only "$shared_lib") |
    awk 'NF == 3 {print $3}' | grep -E '^(cuda|__cuda|libcudart|cudart)' || true)
if [[ -n "$cudart" ]]; then
    echo "CUDA runtime symbols are visible:"; echo "$cudart" | head -20; status=1
fi
foreign=$(nm -g --defined-only "$static_lib" 2>/dev/null | awk 'NF == 3 && $2 ~ /^[TDBR]$/ {print $3}' | is_own || true)
if [[ -n "$foreign" ]]; then
    echo "$static_lib defines foreign strong symbols:"; echo "$foreign" | head -20; status=1
fi
exported=$(nm -D --defined-only "$shared_lib" | awk 'NF == 3 {print $3}' | is_own || true)
if [[ -n "$exported" ]]; then
    echo "$shared_lib exports foreign symbols:"; echo "$exported" | c++filt | head -20; status=1
fi
dynamic=$(nm -D --defined-only "$shared_lib" | awk 'NF == 3 {print $3}')
count=$(echo "$dynamic" | wc -l)
if (( count < 50 )); then
    echo "$shared_lib exports only $count symbols: the API is missing"; status=1
fi
internal=$(echo "$dynamic" | c++filt | grep -E 'detail::|::Impl::|::Access::' || true)
if [[ -n "$internal" ]]; then
    echo "$shared_lib exports internals:"; echo "$internal" | head -20; status=1
fi
for needed in hmsm_simulation_create _ZN4hmsm10Simulation6createERKNS_5SceneERKNS_16SimulationConfigE; do
    if ! grep -qx "$needed" <<<"$dynamic"; then
        echo "$shared_lib does not export $needed"; status=1
    fi
done
(( status == 0 )) && echo "symbols ok: $count exported from $(basename "$shared_lib"), no foreign definitions"
exit $status
