# Sourced by run-example.sh and run-tests.sh, not run on its own: envconv_install creates the
# venv ($venv) if it is missing and installs envconv into it, building the native core. Each
# stage says what it does on stderr, and a stage that runs long says so every 30 s: the first
# build of the core takes a few minutes (later runs recompile only what changed).

_stage() { printf '%s: %s\n' "${0##*/}" "$*" >&2; }

# Run "$@", saying every 30 s that "$1" still runs; the ticker (and its sleep) ends with the
# command, or on its own within 30 s if this script is gone.
_with_ticker() {
    local label=$1 start=$SECONDS status=0 ticker
    shift
    (
        pid=""
        trap 'kill "$pid" 2>/dev/null; exit 0' TERM
        while :; do
            sleep 30 &
            pid=$!
            wait "$pid" && kill -0 "$$" 2>/dev/null || exit 0
            _stage "$label: still running, $((SECONDS - start)) s so far"
        done
    ) &
    ticker=$!
    "$@" || status=$?
    kill "$ticker" 2>/dev/null || true
    wait "$ticker" 2>/dev/null || true
    return "$status"
}

# envconv_install TARGET: TARGET is what pip installs, "." or ".[test]".
envconv_install() {
    if [ ! -x "$venv/bin/python" ]; then
        _stage "creating the virtual environment $venv"
        python3 -m venv "$venv"
    fi
    _stage "installing pip and the build tools (scikit-build-core, nanobind, CMake, Ninja) into $venv"
    _with_ticker "installing pip" "$venv/bin/python" -m pip install --quiet --upgrade pip
    # The build requirements live in the venv, so that the build folder (build/) is reused and
    # a rebuild after editing src/core/ compiles only what changed.
    _with_ticker "installing the build tools" \
        "$venv/bin/python" -m pip install --quiet scikit-build-core nanobind cmake ninja
    _stage "installing envconv ($1) and building its native core: a few minutes the first time"
    _with_ticker "building envconv" \
        "$venv/bin/python" -m pip install --quiet --no-build-isolation -e "$1"
    _stage "installed $(cd "$venv/bin" && pwd)/envconv (put that folder on PATH to type envconv)"
}
