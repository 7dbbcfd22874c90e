#!/bin/sh
# End-to-end tests of the `ctcsim` command line: every command, its output formats and its
# documented exit codes, run on the real binary ($CTCSIM) with jobs written here.
# Prints one line per failure and a closing "cli: N passed, N failed"; exits non-zero on failure.
set -u
CTCSIM=${CTCSIM:-build/ctcsim}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
. "$(dirname "$0")/lib.sh"

# expect_exit CODE NAME COMMAND...: runs the command, stdout to $tmp/out, stderr to $tmp/err,
# stopped after CLI_TIME_LIMIT seconds (default 120; each takes well under a second)
expect_exit() {
    want=$1 name=$2
    shift 2
    timeout -k 5 "${CLI_TIME_LIMIT:-120}" "$@" >"$tmp/out" 2>"$tmp/err"
    got=$?
    if [ "$got" -eq 124 ] || [ "$got" -eq 137 ]; then
        fail "$name: stopped after ${CLI_TIME_LIMIT:-120} s (CLI_TIME_LIMIT)"
    elif [ "$got" -eq "$want" ]; then pass; else
        fail "$name: exit $got, expected $want"
        sed 's/^/    /' "$tmp/err" | head -n 5
    fi
}

# expect_grep NAME FILE PATTERN: the file has a line matching the fixed string
expect_grep() {
    if grep -qF -- "$3" "$2"; then pass; else fail "$1: no \"$3\" in $2"; fi
}

# a small PD job: two rods, 0.5 s sampled every 0.1 s
cat >"$tmp/job.json" <<'EOF'
{
  "name": "two rods",
  "scene": {
    "bodies": [
      {"mass": 1, "shape": {"type": "rod", "end": [0, -1, 0]},
       "joint": {"type": "revolute", "axis": [0, 0, 1]}},
      {"mass": 1, "shape": {"type": "rod", "end": [0, -1, 0]},
       "joint": {"type": "revolute", "axis": [0, 0, 1], "location": [0, -1, 0]}}
    ],
    "q0": [0.5, -0.5]
  },
  "controller": {"type": "pd", "kp": 100, "kv": 20},
  "trajectory": {"type": "constant", "value": 0},
  "duration": 0.5,
  "output": {"interval": 0.1}
}
EOF

# listing and printing presets
expect_exit 0 "presets" "$CTCSIM" presets
expect_grep "presets lists the triple pendulum" "$tmp/out" "triple_pendulum_pid"
expect_grep "presets lists the n-link pendulum" "$tmp/out" "n_link_pendulum"
expect_exit 0 "preset prints JSON" "$CTCSIM" preset triple_pendulum_pid
cp "$tmp/out" "$tmp/preset.json"
expect_grep "preset has the paper's ki" "$tmp/preset.json" '"ki":'
expect_exit 0 "a printed preset validates" "$CTCSIM" validate "$tmp/preset.json"
expect_exit 0 "preset with a parameter" "$CTCSIM" preset n_link_pendulum n=5
expect_exit 2 "preset with a bad parameter" "$CTCSIM" preset n_link_pendulum n=1
expect_exit 2 "unknown preset" "$CTCSIM" preset no_such_thing

# run: CSV to stdout, 6 samples + header
expect_exit 0 "run csv" "$CTCSIM" run "$tmp/job.json"
[ "$(wc -l <"$tmp/out")" -eq 7 ] && pass || fail "run csv: $(wc -l <"$tmp/out") lines, expected 7"
head -n 1 "$tmp/out" | grep -q '^t,q\[0\],q\[1\],qdot\[0\],qdot\[1\],q_des\[0\]' && pass ||
    fail "run csv header: $(head -n 1 "$tmp/out")"
tail -n 1 "$tmp/out" | grep -q '^0.5,' && pass || fail "run csv: the last row is not t = 0.5"
expect_grep "run summary" "$tmp/err" "two rods: done, planar pd, 6 samples"

# channels, decimation, output file, JSON, standard input
expect_exit 0 "run --channels --every" "$CTCSIM" run "$tmp/job.json" --channels e,tau --every 2
[ "$(head -n 1 "$tmp/out")" = "t,e[0],e[1],tau[0],tau[1]" ] && pass ||
    fail "run --channels header: $(head -n 1 "$tmp/out")"
[ "$(wc -l <"$tmp/out")" -eq 5 ] && pass || fail "run --every 2: $(wc -l <"$tmp/out") lines, expected 5 (samples 0, 2, 4 and the last)"
expect_exit 0 "run json to file" "$CTCSIM" run "$tmp/job.json" --format json -o "$tmp/r.json" --quiet
[ ! -s "$tmp/out" ] && [ ! -s "$tmp/err" ] && pass || fail "run -o --quiet wrote to stdout/stderr"
expect_grep "json has the status" "$tmp/r.json" '{"status":"done","spec":{'
expect_grep "json has metrics" "$tmp/r.json" '"errdyn_dev":'
expect_grep "json has the columnar series" "$tmp/r.json" '"series":{"t":[0,0.10000000000000001,'
expect_exit 0 "run from stdin" sh -c "\"$CTCSIM\" run - <\"$tmp/job.json\""

# a preset with another controller: the summary names the controller run, not the preset's
echo '{"preset": "triple_pendulum_pid", "duration": 0.2, "controller": {"type": "lqr", "Q": [1, 1, 1], "lambda": 0.01}}' >"$tmp/lqr.json"
expect_exit 0 "run a preset with another controller" "$CTCSIM" run "$tmp/lqr.json" -o "$tmp/lqr.csv"
expect_grep "its summary names the controller" "$tmp/err" "Triple pendulum, LQR (scene of Kingsley et al. 2017, sec. 7.1): done, planar lqr,"

# long chains: a default run of 4096 rods whose controller has a model of its own (the plant's
# literal forward pass) floors its tolerances on the accelerations' rounding and says so
# (src/sim/sim_tol.c); with the exact model the plant's pass starts from u (sim_rhs.c), its
# accelerations carry no such rounding and nothing is floored; 65536 rods, the job format's
# limit, run 3 ms of CTC with rk4 without diverging (every |e| stays at its start, pi/6, to
# 1e-2), and 65537 are refused
echo '{"preset": "n_link_pendulum", "n": 4096, "duration": 0.1, "controller": {"model": {"mass_scale": 1.1}}}' >"$tmp/n4096.json"
expect_exit 0 "a default run of 4096 rods, model error" "$CTCSIM" run "$tmp/n4096.json" -o "$tmp/n4096.csv"
expect_grep "its tolerance floor is reported" "$tmp/err" "tolerance floor: atol 1e-10 raised to "
echo '{"preset": "n_link_pendulum", "n": 4096, "duration": 0.1}' >"$tmp/n4096x.json"
expect_exit 0 "a default run of 4096 rods, exact model" "$CTCSIM" run "$tmp/n4096x.json" -o "$tmp/n4096x.csv"
if grep -q "tolerance floor" "$tmp/err"; then fail "the exact model's run was floored: $(cat "$tmp/err")"; else pass; fi
grep -qE "error-dynamics deviation [0-9.]+e-(09|1[0-9])" "$tmp/err" && pass ||
    fail "the exact model's error dynamics: $(cat "$tmp/err")"
echo '{"preset": "n_link_pendulum", "n": 65536, "duration": 0.003, "integrator": {"method": "rk4", "step": 0.001}, "output": {"interval": 0.001, "channels": ["e"]}}' >"$tmp/n65536.json"
expect_exit 0 "3 ms of CTC on 65536 rods" "$CTCSIM" run "$tmp/n65536.json" -o "$tmp/n65536.csv"
expect_grep "65536 rods done" "$tmp/err" "done, planar pd, 4 samples to t = 0.003 s"
if awk -F, 'NR > 1 { for (i = 2; i <= NF; i++) if ($i > 0.534 || $i < -0.534) bad = 1 } END { exit bad || NR != 5 }' "$tmp/n65536.csv"; then
    pass
else
    fail "65536 rods: an error left pi/6 by more than 1e-2 (or not 4 samples)"
fi
expect_exit 2 "65537 rods refused" "$CTCSIM" preset n_link_pendulum n=65537
expect_grep "65537 rods named" "$tmp/err" "must be an integer from 2 to 65536 (got 65537)"

expect_exit 1 "no command" "$CTCSIM"
expect_exit 1 "unknown command" "$CTCSIM" fly
expect_exit 1 "bad format" "$CTCSIM" run "$tmp/job.json" --format xml
expect_exit 1 "bad channel" "$CTCSIM" run "$tmp/job.json" --channels q,torque
expect_grep "bad channel named" "$tmp/err" 'unknown channel "torque"'
expect_exit 4 "missing file" "$CTCSIM" run "$tmp/nope.json"
expect_grep "missing file named" "$tmp/err" "nope.json: No such file or directory"
sed 's/"mass": 1, "shape"/"mass": -1, "shape"/' "$tmp/job.json" >"$tmp/bad.json"
expect_exit 2 "invalid job" "$CTCSIM" run "$tmp/bad.json"
expect_grep "invalid job names the field" "$tmp/err" "bad.json: scene.bodies[0].mass: "
expect_exit 2 "validate an invalid job" "$CTCSIM" validate "$tmp/bad.json"
sed 's/"kp": 100/"kp": 100, "kq": 3/' "$tmp/job.json" >"$tmp/typo.json"
expect_exit 2 "unknown key" "$CTCSIM" validate "$tmp/typo.json"
expect_grep "unknown key named" "$tmp/err" "controller.kq"
sed 's/"duration": 0.5/"duration": 0.5, "limits": {"max_speed": 0.01}/' "$tmp/job.json" \
    >"$tmp/diverge.json"
expect_exit 3 "a diverging run" "$CTCSIM" run "$tmp/diverge.json"
expect_grep "divergence reported" "$tmp/err" "exceeds the bound 0.01"

# closed chains: the five-bar runs with one e column per independent coordinate and the loop's
# residuals; a loop whose independent coordinates do not match its mobility is invalid (exit 2)
expect_exit 0 "presets lists the five-bar" "$CTCSIM" presets
expect_grep "presets lists the five-bar" "$tmp/out" "five_bar_pd"
expect_grep "presets lists the RSSR linkage" "$tmp/out" "rssr_passive"
echo '{"preset": "five_bar_pd", "duration": 0.5, "output": {"interval": 0.1}}' >"$tmp/five_bar.json"
expect_exit 0 "run five_bar_pd" "$CTCSIM" run "$tmp/five_bar.json"
head -n 1 "$tmp/out" | grep -q ',e\[0\],e\[1\],e\[2\],tau\[0\],' && pass ||
    fail "five-bar header: no e[0..2] before tau: $(head -n 1 "$tmp/out")"
head -n 1 "$tmp/out" | grep -q 'e\[3\]' && fail "five-bar header has e[3]: three coordinates are independent" || pass
head -n 1 "$tmp/out" | grep -q ',loop\[position\],loop\[velocity\]$' && pass ||
    fail "five-bar header: no loop columns at the end: $(head -n 1 "$tmp/out")"
[ "$(wc -l <"$tmp/out")" -eq 7 ] && pass || fail "run five_bar_pd: $(wc -l <"$tmp/out") lines, expected 7"
expect_grep "five-bar summary" "$tmp/err" "five_bar_pd, duration = 0.5, output.interval = 0.1: done, planar pd"
expect_grep "five-bar summary reports the loop" "$tmp/err" ", loop residual "
expect_exit 0 "five-bar json" "$CTCSIM" run "$tmp/five_bar.json" --format json -o "$tmp/five_bar_out.json" --quiet
expect_grep "json has the loop metrics" "$tmp/five_bar_out.json" '"loop":{"residual_max":'
expect_grep "json names the controlled coordinates" "$tmp/five_bar_out.json" '"coordinates":[{"joint":0,"coordinate":0},{"joint":1,"coordinate":1},{"joint":2,"coordinate":2}]'
expect_exit 0 "run five_bar_pd --channels loop" "$CTCSIM" run "$tmp/five_bar.json" --channels loop
[ "$(head -n 1 "$tmp/out")" = "t,loop[position],loop[velocity]" ] && pass ||
    fail "run --channels loop header: $(head -n 1 "$tmp/out")"
echo '{"preset": "five_bar_pd", "scene": {"loop": {"joint": {"independent": true}}},
  "trajectory": {"type": "constant", "value": 0}}' >"$tmp/mobility.json"
expect_exit 2 "a loop of 4 independent coordinates and mobility 3" "$CTCSIM" run "$tmp/mobility.json"
expect_grep "the mobility is named" "$tmp/err" "mobility.json: scene.loop: "
expect_grep "the mobility is named" "$tmp/err" "mobility"
expect_exit 2 "validate the same" "$CTCSIM" validate "$tmp/mobility.json"
echo '{"preset": "five_bar_pd", "duration": 0.1}' >"$tmp/five_bar_short.json"
expect_exit 0 "validate a loop" "$CTCSIM" validate "$tmp/five_bar_short.json"
expect_grep "validate counts the independent coordinates" "$tmp/err" "valid (5 bodies and a loop, 5 coordinates, 3 independent, controller pd)"
expect_grep "the normalised loop" "$tmp/out" '"cond_max":'

# a loop closed on a body: the arm's four-bar, with a dependent joint outside the loop refused
echo '{"preset": "arm_four_bar_pd", "duration": 0.2}' >"$tmp/arm.json"
expect_exit 0 "run a loop closed on a body" "$CTCSIM" run "$tmp/arm.json" -o "$tmp/arm.csv"
expect_grep "the summary reports its loop" "$tmp/err" ", loop residual "
echo '{"preset": "arm_four_bar_pd", "scene": {"loop": {"body": 3}}}' >"$tmp/arm_bad.json"
expect_exit 2 "a loop on the tip itself" "$CTCSIM" validate "$tmp/arm_bad.json"
expect_grep "the body is named" "$tmp/err" "scene.loop.body: must be the index of a body before the tip"

# bodies that name their parent: validate writes each parent as an index; a bad one is refused
cat >"$tmp/named.json" <<'EOF'
{"scene": {"bodies": [
  {"name": "upper", "parent": "ground", "mass": 1, "shape": {"type": "rod", "end": [0, -1, 0]},
   "joint": {"type": "revolute", "axis": [0, 0, 1]}},
  {"name": "lower", "parent": "upper", "mass": 1, "shape": {"type": "rod", "end": [0, -1, 0]},
   "joint": {"type": "revolute", "axis": [0, 0, 1], "location": [0, -1, 0]}}]},
 "controller": {"type": "none"}, "duration": 0.1}
EOF
expect_exit 0 "validate parents given by name" "$CTCSIM" validate "$tmp/named.json"
expect_grep "the first body's parent is the ground" "$tmp/out" '"parent":	-1,'
expect_grep "the second body's parent is body 0" "$tmp/out" '"parent":	0,'
sed 's/"parent": "upper"/"parent": "lower"/' "$tmp/named.json" >"$tmp/named_bad.json"
expect_exit 2 "a body its own parent" "$CTCSIM" validate "$tmp/named_bad.json"
expect_grep "the parent's field and reason" "$tmp/err" 'scene.bodies[1].parent: "lower" must name a body before body 1 (it names body 1)'

# a tree preset: validate lists its parents (the Y's right branch on the arm, body 0)
"$CTCSIM" preset y_pendulum_pd >"$tmp/y.json"
expect_exit 0 "validate the Y tree" "$CTCSIM" validate "$tmp/y.json"
expect_grep "validate lists a tree's parents" "$tmp/err" "valid (5 bodies in a tree, parents -1 0 1 0 3, 5 coordinates, controller pd)"
expect_grep "the normalised Y's right branch hangs from the arm" "$tmp/out" '"parent":	0,'
# import: a URDF arm and a DH table become complete jobs that run; bad input exits 2 naming the
# element and its line
cat >"$tmp/arm.urdf" <<'EOF'
<?xml version="1.0"?>
<robot name="two_link_arm">
  <link name="base"/>
  <link name="upper">
    <inertial><origin xyz="0.5 0 0"/><mass value="1"/>
      <inertia ixx="1e-4" iyy="0.0833" izz="0.0833"/></inertial>
  </link>
  <link name="fore">
    <inertial><origin xyz="0.5 0 0"/><mass value="1"/>
      <inertia ixx="1e-4" iyy="0.0833" izz="0.0833"/></inertial>
  </link>
  <joint name="shoulder" type="continuous">
    <parent link="base"/><child link="upper"/><axis xyz="0 0 1"/>
  </joint>
  <joint name="elbow" type="revolute">
    <parent link="upper"/><child link="fore"/><origin xyz="1 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="30" velocity="3"/>
  </joint>
</robot>
EOF
expect_exit 0 "import a URDF" "$CTCSIM" import "$tmp/arm.urdf"
cp "$tmp/out" "$tmp/arm_job.json"
expect_grep "the imported job is named after the robot" "$tmp/arm_job.json" '"name":	"two_link_arm"'
expect_grep "the imported job has its bodies" "$tmp/arm_job.json" '"name":	"fore"'
expect_grep "the imported job keeps the joint limit" "$tmp/arm_job.json" '"effort":	30'
expect_grep "the imported job has a minimum-jerk move" "$tmp/arm_job.json" '"type":	"min_jerk"'
expect_exit 0 "the imported job runs" "$CTCSIM" run "$tmp/arm_job.json" -o "$tmp/arm_run.csv"
expect_grep "the imported job runs with PD" "$tmp/err" "two_link_arm: done, spatial pd"
cat >"$tmp/dh.json" <<'EOF'
{"convention": "standard", "rows": [
  {"a": 0.5, "alpha": 1.5707963267948966, "d": 0.3, "mass": 2, "com": [-0.25, 0, 0],
   "inertia": [0.002, 0.04, 0.04]},
  {"type": "prismatic", "a": 0, "alpha": 0, "d": 0.2, "theta": 0.3, "mass": 1,
   "com": [0, 0, -0.1], "inertia": [0.01, 0.01, 0.001]}]}
EOF
expect_exit 0 "import a DH table" "$CTCSIM" import --dh "$tmp/dh.json"
cp "$tmp/out" "$tmp/dh_job.json"
expect_exit 0 "the imported DH job runs" "$CTCSIM" run "$tmp/dh_job.json" -o "$tmp/dh_run.csv"
expect_grep "the DH job is named after its file" "$tmp/err" "dh: done, spatial pd"
printf '<robot name="r">\n<link name="a">\n</robot>\n' >"$tmp/unclosed.urdf"
expect_exit 2 "import an unclosed tag" "$CTCSIM" import "$tmp/unclosed.urdf"
expect_grep "the unclosed tag is named with its line" "$tmp/err" "unclosed.urdf: scene.urdf: line 3: not well-formed XML: Opening and ending tag mismatch: link line 2 and robot"
sed 's/type="continuous"/type="floating"/' "$tmp/arm.urdf" >"$tmp/floating.urdf"
expect_exit 2 "import a floating joint" "$CTCSIM" import "$tmp/floating.urdf"
expect_grep "the floating joint is named with its line" "$tmp/err" 'floating.urdf: scene.urdf: line 12: <joint name="shoulder">: type "floating" is not supported'
echo '{"convention": "craig", "rows": []}' >"$tmp/dh_bad.json"
expect_exit 2 "import a bad DH table" "$CTCSIM" import --dh "$tmp/dh_bad.json"
expect_grep "the DH field is named" "$tmp/err" "dh_bad.json: scene.dh.convention: "
expect_exit 1 "import without a file" "$CTCSIM" import
expect_exit 4 "import a missing file" "$CTCSIM" import "$tmp/nope.urdf"

# every example job of the API documentation is valid
for example in api/examples/*.json; do
    expect_exit 0 "validate $example" "$CTCSIM" validate "$example"
done

# every example family is valid (the 4096-link one is only expanded here, not run)
for example in api/examples/families/*.json; do
    expect_exit 0 "sweep --validate $example" "$CTCSIM" sweep "$example" --validate
    expect_grep "$example is valid" "$tmp/err" "$example: valid family "
done

# sweep: a family run on two threads prints its table, one row per member in member order,
# the same cells as CSV and aligned; no progress bar when standard error is not a terminal
gains=api/examples/families/gains_triple_pendulum.json
expect_exit 0 "sweep --csv" "$CTCSIM" sweep "$gains" --csv --threads 2
cp "$tmp/out" "$tmp/sweep.csv"
expect_grep "the table's header" "$tmp/sweep.csv" \
    "member,replica,controller.kp,controller.kv,status,e_final,e_rms,e_max,tau_peak,energy_drift,us_per_eval,steps,wall_s"
expect_grep "member 0: kp 10, kv 5" "$tmp/sweep.csv" "0,0,10,5,done,"
expect_grep "member 24: kp 1000, kv 65" "$tmp/sweep.csv" "24,0,1000,65,done,"
expect_grep "the summary" "$tmp/err" "Tracking error against kp and kv, triple pendulum: 25 members on 2 threads, 25 done, 0 stopped early"
if [ "$(wc -l <"$tmp/sweep.csv")" -eq 26 ]; then pass; else fail "sweep --csv: $(wc -l <"$tmp/sweep.csv") lines, not 26"; fi
if [ "$(cut -d, -f1 "$tmp/sweep.csv" | tail -n +2 | tr '\n' ' ')" = "$(seq 0 24 | tr '\n' ' ')" ]; then pass; else fail "sweep --csv: members out of order"; fi
if tr -d '\n' <"$tmp/err" | grep -q "$(printf '\r')"; then fail "sweep drew a progress bar into a pipe"; else pass; fi
expect_exit 0 "sweep aligned" "$CTCSIM" sweep "$gains" --threads 1 --quiet
if [ "$(awk 'NR > 1 { print $1 "," $2 "," $3 "," $4 "," $5 }' "$tmp/out")" = \
    "$(tail -n +2 "$tmp/sweep.csv" | cut -d, -f1-5)" ]; then pass; else fail "sweep: aligned cells differ from the CSV"; fi
if [ -s "$tmp/err" ]; then fail "sweep --quiet wrote to standard error"; else pass; fi
printf '{"base": {"preset": "triple_pendulum_pd"}, "axes": [{"path": "integrator.rtol", "values": [1e-6, 2]}]}' >"$tmp/bad_family.json"
expect_exit 2 "sweep an invalid family" "$CTCSIM" sweep "$tmp/bad_family.json"
expect_grep "the bad member is named" "$tmp/err" \
    "bad_family.json: axes[0]: axis integrator.rtol = 2 (member 1): integrator: rtol must be in (0, 1) (got 2)"
printf '{"base": {"preset": "triple_pendulum_pd", "duration": 0.5, "limits": {"max_speed": 0.01}}, "replicas": 2}' >"$tmp/stop_family.json"
expect_exit 3 "sweep with members stopped early" "$CTCSIM" sweep "$tmp/stop_family.json"
expect_grep "stopped members are rows too" "$tmp/out" "diverged"
expect_exit 1 "sweep without a family" "$CTCSIM" sweep
expect_exit 1 "sweep --threads 0" "$CTCSIM" sweep "$gains" --threads 0
expect_exit 4 "sweep a missing file" "$CTCSIM" sweep "$tmp/nope.json"

finish cli
