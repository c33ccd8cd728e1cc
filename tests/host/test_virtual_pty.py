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
        assert ast.literal_eval(r.stdout.strip()) == ("virtual", "viper", 1)
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
