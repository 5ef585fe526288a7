#!/usr/bin/env bash
# Log::open, the per-subscription row index (made by the first Log::columns), then
# Log::columns and record_batches of every topic instance, and all_column_parts of the
# log, this tree against another commit, in one run: `columns_speed` built against both
# (the other commit checked out as a git worktree under target/), run interleaved, the
# medians and their ratio printed.
#
#   benches/columns_vs.sh COMMIT LOG [RUNS]
#
# The 400 MB benchmark log: target/release/examples/inflate
# ../shared/testdata/ulog/pyulog/sample_log_small.ulg /tmp/big.ulg
set -euo pipefail
cd "$(dirname "$0")/.."
commit=$1 log=$2 runs=${3:-9}
work="$PWD/target/columns-vs"
old="$work/$(git rev-parse --short "$commit")"
mkdir -p "$work"
[ -d "$old" ] || git worktree add --detach "$old" "$commit" > /dev/null
# A crate of its own over the other commit's library, building the same source.
crate="$work/bench-$(basename "$old")"
mkdir -p "$crate/src"
cat > "$crate/Cargo.toml" <<TOML
[package]
name = "columns-speed-old"
version = "0.0.0"
edition = "2024"
[dependencies]
ulog-runtime = { path = "$old/ulog-runtime", features = ["arrow"] }
[workspace]
TOML
cp benches/src/bin/columns_speed.rs "$crate/src/main.rs"
cargo build --quiet --release --manifest-path "$crate/Cargo.toml" --target-dir "$work/target"
cargo build --quiet --release -p ulog-benches --bin columns_speed
python3 - "$work/target/release/columns-speed-old" target/release/columns_speed "$log" "$runs" "$commit" <<'PY'
import statistics, subprocess, sys
old, new, log, runs, commit = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5]
times = {}
for r in range(runs):
    for b in ([old, new] if r % 2 == 0 else [new, old]):
        for line in subprocess.run([b, log], capture_output=True, text=True, check=True).stdout.splitlines():
            what, secs, _ = line.split()
            times.setdefault((b, what), []).append(float(secs))
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
print(f"CPU: {cpu}; {runs} runs each, interleaved; log {log}")
for what in ("open", "index", "columns", "batches", "all"):
    o, n = statistics.median(times[(old, what)]), statistics.median(times[(new, what)])
    print(f"  {what:8} {commit}: {o:.3f} s   this tree: {n:.3f} s   speed-up {o / n:.2f}x")
PY
