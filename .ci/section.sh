# Sourced by .ci/run and .ci/embedded.sh: `section NAME` starts a section and
# prints the seconds the one before it took, so a slow step shows in the log
# (CI keeps the log of a failed run; keep the whole run under 30 min).
ci_start=$SECONDS
section_start=$SECONDS
section() {
    printf '\n(%ds; %ds since the start)\n==== %s ====\n' \
        "$((SECONDS - section_start))" "$((SECONDS - ci_start))" "$*"
    section_start=$SECONDS
}
trap 'printf "\n(%ds; %ds in all)\n" "$((SECONDS - section_start))" "$((SECONDS - ci_start))"' EXIT
