#!/bin/sh
# Every public function of a header (each ADASLICE_DEF declaration) is in the
# REFERENCE at the header's top with the very signature it is declared with:
# tests/check_reference.sh HEADER... (make compile-checks runs it).
status=0
for h in "$@"; do
    # the REFERENCE block: from its heading to the next section heading, one line
    ref=$(awk '/^   REFERENCE/ { on = 1; next } on && /^   [A-Z][A-Z]+/ { exit } on' "$h" | tr -s ' \n' '  ')
    # each declaration (not a definition) joined onto one line
    awk '/^ADASLICE_DEF / { d = ""; on = 1 }
         on { d = d " " $0; if (index($0, "{")) on = 0; else if (index($0, ";")) { on = 0; print d } }' "$h" |
        sed 's/^ *ADASLICE_DEF //' | tr -s ' ' ' ' | sed 's/( /(/g' > "${TMPDIR:-/tmp}/check_reference.$$"
    while IFS= read -r decl; do
        case "$ref" in
        *"$decl"*) ;;
        *) echo "$h: REFERENCE lacks or misquotes: $decl"; status=1 ;;
        esac
    done < "${TMPDIR:-/tmp}/check_reference.$$"
    rm -f "${TMPDIR:-/tmp}/check_reference.$$"
done
exit $status
