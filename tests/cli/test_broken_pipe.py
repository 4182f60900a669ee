"""`rbfmu scenes | head -1`: the reader leaving early stops rbfmu without an error message.

Before: "rbfmu: error: [Errno 32] Broken pipe" on stderr, as if the command had failed.
"""

from __future__ import annotations

import subprocess
import sys


def test_a_reader_that_leaves_stops_rbfmu_quietly():
    p = subprocess.Popen([sys.executable, "-m", "fmu.cli", "scenes"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert p.stdout is not None and p.stderr is not None
    p.stdout.close()  # before rbfmu writes (its start-up takes ~1 s): its first write meets a closed pipe
    err = p.stderr.read().decode()
    assert p.wait(timeout=120) == 141, err  # 128 + SIGPIPE, as a Unix tool stopped by the same
    assert err == ""
