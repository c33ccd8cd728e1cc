"""The virtual board is what the host talks to when there is no hardware:
the device image under the MicroPython unix port, on a pty, driven with the
mpremote command line exactly as a board would be (`connect <pty> resume
exec`), its refresh paced by the wall clock in a background thread."""
import pytest
import ast
import time

from support.vboard import mpremote, virtual_board

pytestmark = [pytest.mark.vboard]

STATUS = ("import texel.app as app; st = app.status(); "
          "print(repr({k: st.get(k) for k in ('running', 'board', 'refresh', 'refreshes', "
          "'overruns', 'faults', 'scene')}))")


def _status(port):
    r = mpremote(port, STATUS)
    assert r.returncode == 0, r.stderr
    return ast.literal_eval(r.stdout.strip().splitlines()[-1])


def test_mpremote_drives_the_realtime_virtual_board():
    with virtual_board() as port:
        r = mpremote(port, "import texel.app as app; st = app.start('virtual', realtime=True); "
                           "print(repr((st['board'], st['refresh'], st['protocol'])))")
        assert r.returncode == 0, r.stderr
        assert ast.literal_eval(r.stdout.strip()) == ("virtual", "viper", 3)
        time.sleep(0.5)
        st1 = _status(port)
        assert st1["running"] is True and st1["faults"] == 0
        assert st1["refreshes"] > 0                      # the loop runs between host calls
        # a push crosses as a literal; the board confirms what now plays
        scene = {"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {
            "kind": "texel", "pitch_db": 3.0, "irregularity_db": -10.0, "seed": 1}}]}
        r = mpremote(port, "import texel.app as app; st = app.push(%r); "
                           "print(repr(st['scene']['regions'][0]['pitch_db']))" % (scene,))
        assert r.returncode == 0, r.stderr
        assert ast.literal_eval(r.stdout.strip()) == 3.0
        # a bad scene is refused with the device's own message; nothing changes
        # (a finite value: repr(nan) is not a literal - the host's link must
        # spell non-finite floats out itself)
        bad = {"regions": [{"start_mm": 0, "end_mm": 10, "texture": {
            "kind": "texel", "pitch_db": 99.0, "irregularity_db": -10.0}}]}
        r = mpremote(port, "import texel.app as app\ntry:\n    app.push(%r)\n    print('pushed')\n"
                           "except ValueError as e:\n    print(repr(str(e)))" % (bad,))
        assert r.returncode == 0, r.stderr
        msg = ast.literal_eval(r.stdout.strip())
        assert msg.startswith("regions[0].texture.pitch_db: 99.0 is out of range"), msg
        st2 = _status(port)
        assert st2["scene"]["regions"][0]["pitch_db"] == 3.0
        assert st2["refreshes"] > st1["refreshes"]       # still playing, never reset
        r = mpremote(port, "import texel.app as app; app.stop(); print(app.status()['running'])")
        assert r.stdout.strip() == "False"


def test_a_plain_mpremote_exec_on_the_virtual_board_then_push_works(capsys):
    """The teacher's plain `mpremote connect PORT exec "..."` (a soft reset before and after,
    issue 30) on the playing virtual board, as typed: it answers, the soft reset stops the
    display as a board's raw-REPL reset does (status: running False - the carrier is off),
    and the next `texelpad status` works; `texelpad push` says in one line how to start
    it, and `push --board virtual` plays again."""
    import os
    import subprocess
    import sys
    from support.cli import run_cli
    exe = os.path.join(os.path.dirname(sys.executable), "mpremote")
    with virtual_board() as port:
        r = mpremote(port, "import texel.app as app; app.start('virtual', realtime=True)")
        assert r.returncode == 0, r.stderr
        assert _status(port)["running"] is True
        for _ in range(2):
            p = subprocess.run([exe, "connect", port, "exec",
                                "import texel.app as app; print(app.status()['running'])"],
                               capture_output=True, text=True, timeout=60)
            assert p.returncode == 0 and p.stdout.strip() == "False", p.stdout + p.stderr
        code, out, err = run_cli(capsys, "status", "--port", port)
        assert code == 0 and out.startswith("texelpad is not running"), out + err
        code, out, err = run_cli(capsys, "push", "--port", port, "--reference", "4sin")
        assert code == 1 and err.count("\n") == 1 and "--board" in err, err
        code, out, err = run_cli(capsys, "push", "--port", port, "--board", "virtual",
                                 "--reference", "4sin")
        assert code == 0 and "reference 4sin" in out, err
        time.sleep(0.3)
        st = _status(port)
        assert st["running"] and st["refreshes"] > 0 and st["faults"] == 0
