# Sourced by scripts/ab.sh and scripts/icount.sh: their common arguments,
#   BASE_BIN OTHER_BIN... -- SCENE.xml:METHOD[:ARG,ARG...]...
# `parse_builds NAME USAGE "$@"` sets `name`, `bins` (the builds, each checked executable) and `specs`
# (the workloads), exiting with status 2 and a message naming NAME on bad arguments;
# `parse_spec SPEC` sets `scene`, `method` and `args` (space-separated) and checks the scene.
parse_builds() {
  local usage=$2
  name=$1
  shift 2
  bins=()
  while [ $# -gt 0 ] && [ "$1" != "--" ]; do bins+=("$1"); shift; done
  [ "${1:-}" = "--" ] || { echo "usage: $usage" >&2; exit 2; }
  shift
  [ ${#bins[@]} -ge 2 ] && [ $# -ge 1 ] || { echo "$name: give at least two builds and one workload" >&2; exit 2; }
  for b in "${bins[@]}"; do [ -x "$b" ] || { echo "$name: $b is not an executable" >&2; exit 2; }; done
  specs=("$@")
}

parse_spec() {
  local rest
  scene=${1%%:*}; rest=${1#*:}; method=${rest%%:*}; args=""
  [ "$rest" != "$method" ] && args=$(echo "${rest#*:}" | tr ',' ' ')
  [ -f "$scene" ] || { echo "$name: no scene $scene" >&2; exit 2; }
}
