#!/usr/bin/env bash
# Regenerates the generated chain models in mjcf/ (mjcf/tree.xml is hand-written).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
gen=("/usr/bin/python3" "$here/tools/gen_chain.py")
mkdir -p "$here/mjcf"
"${gen[@]}" -n 4 --name arm4 -o "$here/mjcf/arm4.xml"
for n in 8 16 24 32; do
  "${gen[@]}" -n "$n" --name "chain$n" -o "$here/mjcf/chain$n.xml"
done
"${gen[@]}" -n 8 --nonplanar --name chain8_spatial -o "$here/mjcf/chain8_spatial.xml"
