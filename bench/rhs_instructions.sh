#!/bin/sh
# The instructions one CTC right-hand side executes, this tree against another commit, counted by
# callgrind (exact and repeatable, where wall time on a shared machine hides a few percent):
#   sh bench/rhs_instructions.sh REV
# builds REV (in a temporary git worktree) and this tree with the benchmarks' flags less
# -march=native (valgrind 3.19 decodes no AVX-512; x86-64-v3 keeps AVX2 and FMA), runs four jobs
# on fixed RK4 steps (so both take the same steps) under callgrind, and prints the instructions
# inclusive in sim_rhs, the integrator's right-hand side, per job and their ratio.
set -eu
rev=${1:?usage: sh bench/rhs_instructions.sh REV}
cd "$(dirname "$0")/.."
command -v valgrind >/dev/null || { echo "valgrind not found (apt-get install valgrind)"; exit 1; }
opt="-O3 -fno-tree-vectorize -march=x86-64-v3 -ffp-contract=fast -DNDEBUG"
tmp=$(mktemp -d)
trap 'git worktree remove --force "$tmp/base" >/dev/null 2>&1; rm -rf "$tmp"' EXIT INT TERM
git worktree add -q --detach "$tmp/base" "$rev"
make -s -C "$tmp/base" BUILD=build/rhs OPT="$opt" build/rhs/ctcsim >/dev/null
make -s BUILD=build/rhs OPT="$opt" build/rhs/ctcsim >/dev/null

cat >"$tmp/1.json" <<'EOF'
{"preset": "triple_pendulum_pid", "integrator": {"method": "rk4", "step": 0.001}, "duration": 2}
EOF
cat >"$tmp/2.json" <<'EOF'
{"preset": "spatial_double_pendulum_pid", "integrator": {"method": "rk4", "step": 0.001},
 "duration": 2}
EOF
cat >"$tmp/3.json" <<'EOF'
{"preset": "n_link_pendulum", "n": 64, "integrator": {"method": "rk4", "step": 0.001},
 "duration": 0.5}
EOF
cat >"$tmp/4.json" <<'EOF'
{"preset": "five_bar_pd", "integrator": {"method": "rk4", "step": 0.001}, "duration": 1}
EOF

# instructions inclusive in the function named sim_rhs, from a callgrind output file
rhs() {
    callgrind_annotate --inclusive=yes "$1" 2>/dev/null | grep -m 1 ':sim_rhs \[' |
        awk '{gsub(",", "", $1); print $1}'
}
printf '%-30s %14s %14s %7s\n' job "$rev" "this tree" ratio
for k in 1 2 3 4; do
    valgrind --tool=callgrind --callgrind-out-file="$tmp/base.$k" \
        "$tmp/base/build/rhs/ctcsim" run "$tmp/$k.json" -o /dev/null >/dev/null 2>&1
    valgrind --tool=callgrind --callgrind-out-file="$tmp/new.$k" \
        build/rhs/ctcsim run "$tmp/$k.json" -o /dev/null >/dev/null 2>&1
    b=$(rhs "$tmp/base.$k") n=$(rhs "$tmp/new.$k")
    name=$(sed -n 's/.*"preset": "\([a-z_]*\)".*/\1/p' "$tmp/$k.json")
    printf '%-30s %14s %14s %7s\n' "$name" "$b" "$n" "$(echo "scale=4; $n / $b" | bc)"
done
