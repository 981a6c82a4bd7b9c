#!/usr/bin/env bash
# Install the optional scikits.odes IDA backend (pneunet[odes]).
#
# scikits.odes 2.7 has no wheels: pip compiles it against a system SUNDIALS.
# Verified combination: Debian 12 (bookworm) libsundials-dev 6.4.1+dfsg1-3 with
# scikits.odes 2.7.0 (Python 3.11).  Idempotent; always exits 0 — when the
# backend cannot be installed it says why, and tests/test_backends.py skips.
set -u

say() { echo "install-odes: $*"; }
PY=${PYTHON:-python}

if "$PY" -c "import scikits.odes.sundials.ida" 2>/dev/null; then
    say "scikits.odes already importable; nothing to do"
    exit 0
fi

if ! [ -e /usr/include/sundials/sundials_config.h ]; then
    if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
        say "installing Debian libsundials-dev"
        if ! { apt-get update -qq && DEBIAN_FRONTEND=noninteractive \
                apt-get install -y -qq libsundials-dev >/dev/null; }; then
            say "SKIP: apt-get install libsundials-dev failed; odes backend tests will skip"
            exit 0
        fi
    else
        say "SKIP: no system SUNDIALS (/usr/include/sundials) and no root apt-get;"
        say "      install libsundials-dev (SUNDIALS 6.x) first; odes backend tests will skip"
        exit 0
    fi
fi

say "building scikits.odes==2.7.* against $(grep -m1 'SUNDIALS_VERSION ' /usr/include/sundials/sundials_config.h | tr -s ' ')"
if ! "$PY" -m pip install -q "scikits.odes==2.7.*"; then
    say "SKIP: pip install scikits.odes==2.7.* failed; odes backend tests will skip"
    exit 0
fi
if "$PY" -c "import scikits.odes.sundials.ida" 2>/dev/null; then
    say "scikits.odes installed"
else
    say "SKIP: scikits.odes installed but does not import; odes backend tests will skip"
fi
exit 0
