#!/bin/sh
# Seeds the fuzz corpora (not committed) from scenes/ and, when present, ../shared/assets.
set -eu
cd "$(dirname "$0")"
mkdir -p corpus/ron_scene corpus/gltf_model corpus/obj_model
cp ../scenes/*.ron corpus/ron_scene/
cp ../assets/fixture/glint_fixture.gltf corpus/gltf_model/
shared=../../shared/assets
if [ -d "$shared" ]; then
    # Small files only: a fuzzer mutates every byte it is given.
    find "$shared" -name '*.glb' -size -200k -exec cp {} corpus/gltf_model/ \;
    find "$shared" -name '*.gltf' -size -50k -exec cp {} corpus/gltf_model/ \;
    find "$shared" -name '*.obj' -size -200k -exec cp {} corpus/obj_model/ \;
else
    echo "seed.sh: $shared not found; seeding from the repository only" >&2
fi
ls corpus/* | head -0
for d in corpus/*; do echo "$d: $(ls "$d" | wc -l) files"; done
