#!/bin/sh
# The instructions one CTC right-hand side executes, this tree against another commit, counted by
# callgrind (exact and repeatable, where wall time on a shared machine hides a few percent):
#   sh bench/rhs_instructions.sh REV
# builds REV (in a temporary git worktree) and this tree with the benchmarks' flags less
# -march=native (valgrind 3.19 decodes no AVX-512; x86-64-v3 keeps AVX2 and FMA), runs five jobs
# (four presets, and a scene with massless frames on fixed joints) on fixed RK4 steps (so both
# take the same steps) under callgrind, and prints the instructions inclusive in sim_rhs, the
# integrator's right-hand side, per job and their ratio.
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

# a UR5-like arm from a scene with two massless frames (flange, tool0) on fixed joints, which the
# builder merges into the last link for the dynamics (model.h "merged bodies")
cat >"$tmp/5.json" <<'EOF'
{"name": "ur5_tool0_flange",
 "scene": {"gravity": [0, 0, -9.81],
  "bodies": [
   {"name": "shoulder", "mass": 3.7, "shape": {"type": "cylinder", "radius": 0.06, "length": 0.15, "axis": [0, 0, 1], "centre": [0, 0, 0]},
    "joint": {"type": "revolute", "axis": [0, 0, 1], "location": [0, 0, 0.089159]}},
   {"name": "upper_arm", "mass": 8.393, "shape": {"type": "box", "size": [0.12, 0.12, 0.56], "centre": [0, 0, 0.28]},
    "joint": {"type": "revolute", "axis": [0, 1, 0], "location": [0, 0.13585, 0]}},
   {"name": "forearm", "mass": 2.275, "shape": {"type": "box", "size": [0.1, 0.1, 0.5], "centre": [0, 0, 0.25]},
    "joint": {"type": "revolute", "axis": [0, 1, 0], "location": [0, -0.1197, 0.425]}},
   {"name": "wrist_1", "mass": 1.219, "shape": {"type": "box", "size": [0.08, 0.2, 0.08], "centre": [0, 0.093, 0]},
    "joint": {"type": "revolute", "axis": [0, 1, 0], "location": [0, 0, 0.39225]}},
   {"name": "wrist_2", "mass": 1.219, "shape": {"type": "box", "size": [0.08, 0.08, 0.18], "centre": [0, 0, 0.09]},
    "joint": {"type": "revolute", "axis": [0, 0, 1], "location": [0, 0.093, 0]}},
   {"name": "wrist_3", "mass": 0.1879, "shape": {"type": "box", "size": [0.08, 0.12, 0.08], "centre": [0, 0.06, 0]},
    "joint": {"type": "revolute", "axis": [0, 1, 0], "location": [0, 0, 0.09465]}},
   {"name": "flange", "mass": 0, "com": [0, 0, 0], "inertia": [0, 0, 0],
    "joint": {"type": "fixed", "location": [0, 0.07, 0]}},
   {"name": "tool0", "mass": 0, "com": [0, 0, 0], "inertia": [0, 0, 0],
    "joint": {"type": "fixed", "location": [0, 0.0823, 0]}}
  ],
  "q0": [0, -1, 1, 0, 0.5, 0]},
 "controller": {"type": "pd", "zeta": 1, "tau": 0.1},
 "trajectory": [{"type": "sine", "amplitude": 0.5, "period": 2}, {"type": "constant", "value": -1},
   {"type": "constant", "value": 1}, {"type": "sine", "amplitude": 0.3, "period": 1.5},
   {"type": "constant", "value": 0.5}, {"type": "constant", "value": 0}],
 "integrator": {"method": "rk4", "step": 0.001},
 "duration": 1
}
EOF

# instructions inclusive in the function named sim_rhs, from a callgrind output file
rhs() {
    callgrind_annotate --inclusive=yes "$1" 2>/dev/null | grep -m 1 ':sim_rhs \[' |
        awk '{gsub(",", "", $1); print $1}'
}
printf '%-30s %14s %14s %7s\n' job "$rev" "this tree" ratio
for k in 1 2 3 4 5; do
    valgrind --tool=callgrind --callgrind-out-file="$tmp/base.$k" \
        "$tmp/base/build/rhs/ctcsim" run "$tmp/$k.json" -o /dev/null >/dev/null 2>&1
    valgrind --tool=callgrind --callgrind-out-file="$tmp/new.$k" \
        build/rhs/ctcsim run "$tmp/$k.json" -o /dev/null >/dev/null 2>&1
    b=$(rhs "$tmp/base.$k") n=$(rhs "$tmp/new.$k")
    name=$(sed -n 's/.*"\(preset\|name\)": "\([a-z0-9_]*\)".*/\2/p' "$tmp/$k.json" | head -n 1)
    printf '%-30s %14s %14s %7s\n' "$name" "$b" "$n" "$(echo "scale=4; $n / $b" | bc)"
done
