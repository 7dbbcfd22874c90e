#!/bin/sh
# Writes the harnesses' seed corpora (fuzz/README.md) into OUT, from the committed seeds and the
# job documents the project already has:
#   OUT/fuzz_job    fuzz/corpus/job/*, api/examples/*.json, and each preset's document
#                   (`ctcsim preset NAME`, its default parameters)
#   OUT/fuzz_merge  each preset's document followed by each patch of fuzz/corpus/patch/*: the
#                   target and patch fuzz_merge.c reads
# usage: fuzz/corpus.sh CTCSIM OUT   (CTCSIM: the ctcsim program; OUT is emptied first)
set -eu
ctcsim=$1
out=$2
here=$(dirname "$0")
rm -rf "$out/fuzz_job" "$out/fuzz_merge"
mkdir -p "$out/fuzz_job" "$out/fuzz_merge"
cp "$here"/corpus/job/*.json "$out/fuzz_job/"
for f in "$here"/../api/examples/*.json; do cp "$f" "$out/fuzz_job/example_$(basename "$f")"; done
for p in $("$ctcsim" presets | cut -d ' ' -f 1); do
    "$ctcsim" preset "$p" >"$out/fuzz_job/preset_$p.json"
    for patch in "$here"/corpus/patch/*.json; do
        cat "$out/fuzz_job/preset_$p.json" "$patch" \
            >"$out/fuzz_merge/${p}_$(basename "$patch" .json).txt"
    done
done
echo "fuzz/corpus.sh: $(ls "$out/fuzz_job" | wc -l) job seeds, $(ls "$out/fuzz_merge" | wc -l) merge seeds in $out"
