#!/usr/bin/env bash
# A dataset's XDMF views opened by ParaView 5.11 (Debian's python3-paraview, installed on demand
# with python3-meshio; opt-in: CTest label `tools`, `ctest -C tools -R tools.paraview`):
# `paraview.simple.OpenDataFile` must pick Xdmf3ReaderS (ParaView's default for .xdmf) and, like
# the legacy XDMFReader, give one time step per load case and at every time step every solved
# shape with sdf, dirichlet_distance, the two masks, displacement and traction, their shapes and
# their values equal to the shard's (tests/python/xdmf_readers.py); meshio reads every
# shape-*.xdmf the same way. On a 2D P1 dataset of 2 shards and a 3D P2 one.
# Needs HYPERSHAPE_BIN and HYPERSHAPE_SOURCE_DIR (set by CTest); root to install the packages.
. "$(dirname "$0")/../cli/lib.sh"
missing=()
for p in python3-paraview python3-meshio; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "installing ${missing[*]} (ParaView: about 600 MB)"
  export DEBIAN_FRONTEND=noninteractive
  { apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null 2>&1 ||
    { apt-get update -qq && apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null; }; } ||
    { fail "cannot install ${missing[*]}"; finish; exit 1; }
fi

printf 'preset: random2d_p1\nname: pv2\nseed: 5\nshapes: {count: 3, h: 0.1}\nloads: {count: 3}\nrepresentations: {grid_size: 8}\noutput: {shard_size: 2}\n' > "$work/pv2.yaml"
printf 'preset: random3d\nname: pv3\nseed: 7\nshapes: {count: 1}\nloads: {count: 2}\nrepresentations: {grid_size: 8}\n' > "$work/pv3.yaml"
for name in pv2 pv3; do
  "$bin" -q generate "$work/$name.yaml" --progress 0 -o "$work/$name" || { fail "$name: generate"; continue; }
  for reader in paraview meshio; do
    # Offscreen: paraview.simple needs no display for readers.
    if out=$(cd "$work" && PV_NO_DISPLAY=1 /usr/bin/python3 "$src/tests/python/xdmf_readers.py" "$reader" "$work/$name" 2>&1); then
      ok "$name: $reader: $(grep -c '^ok' <<<"$out") checks ($(tail -1 <<<"$out"))"
    else
      fail "$name: $reader"; grep -v '^ok' <<<"$out" | head -20
    fi
  done
done
finish
