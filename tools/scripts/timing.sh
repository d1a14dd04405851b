# Shared by the scripts that time hce against a peer (against-path-tracer.sh, cycles-curve.sh):
# source it after `set -euo pipefail`. It checks the binary and the scene the caller names and
# gives wall-clock timing in seconds.

# require_inputs HCE SCENE: exits 2 with a message when either is missing.
require_inputs() {
    if [[ ! -x "$1" ]]; then
        echo "error: $1 is missing; run: cargo build --release -p hce-tools" >&2
        exit 2
    fi
    if [[ ! -f "$2" ]]; then
        echo "error: no scene at $2" >&2
        exit 2
    fi
}

now() { date +%s.%N; }

# elapsed START END: END - START, two decimals.
elapsed() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", b - a }'; }
