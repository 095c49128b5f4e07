import signal
import subprocess
import sys
import time

from rigkit.script import missing

from conftest import ROOT

HELPER_FAILS = """
import time
from rigkit.script import Helpers, fail
helpers = Helpers("t.py")
try:
    helpers.start("the faults", lambda: 1 / 0)
    time.sleep(30)
except KeyboardInterrupt:
    helpers.check()
    fail("t.py", "stopped", 130)
finally:
    print("cleaned up", flush=True)
"""

STOPPED = """
import time
from rigkit.script import interrupt_on_sigterm
interrupt_on_sigterm()
try:
    print("ready", flush=True)
    time.sleep(30)
except KeyboardInterrupt:
    print("cleaned up", flush=True)
    raise SystemExit(130)
"""


def test_what_is_missing_is_named_with_how_to_install_it() -> None:
    lacking = missing(modules=["rigkit", "no_such_module"], tools=["sh", "nft-absent"])
    assert lacking == [
        "the Python module no_such_module (pip install no_such_module)",
        "nft-absent (apt-get install nft-absent)",
    ]
    assert missing(modules=["iceoryx2_absent"], tools=[]) == [
        "the Python module iceoryx2_absent (pip install iceoryx2_absent)"
    ]


def test_need_ends_the_script_in_one_line() -> None:
    code = "from rigkit.script import need; need('t.py', modules=['mcap_absent'], tools=['nft_absent'])"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 2
    assert done.stderr == (
        "error: t.py: needs the Python module mcap_absent (pip install mcap_absent), "
        "nft_absent (apt-get install nft_absent)\n"
    )


def test_a_failed_helper_thread_ends_the_script_with_its_cleanup() -> None:
    t0 = time.monotonic()
    done = subprocess.run([sys.executable, "-c", HELPER_FAILS], capture_output=True, text=True, timeout=20)
    assert time.monotonic() - t0 < 10
    assert done.returncode == 1, done.stderr
    assert done.stdout == "cleaned up\n"
    assert done.stderr.endswith("error: t.py: helper thread the faults: ZeroDivisionError: division by zero\n")


def test_sigterm_acts_as_ctrl_c() -> None:
    p = subprocess.Popen([sys.executable, "-c", STOPPED], stdout=subprocess.PIPE, text=True)
    assert p.stdout is not None and p.stdout.readline() == "ready\n"
    p.send_signal(signal.SIGTERM)
    out, _ = p.communicate(timeout=10)
    assert (p.returncode, out) == (130, "cleaned up\n")
