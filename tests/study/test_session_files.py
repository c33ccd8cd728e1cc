"""Session files and export as files alone (issue 24, items 2, 5, 7): a file
missing its last newline takes the next record on a line of its own; lab
export leaves a broken session out with the reason and exports the rest, and
refuses a data folder that is missing or holds no session; one holder per
data folder (DataLock), and its port remembered for the next run."""
from __future__ import annotations

import csv
import json
import os
import subprocess
import sys

import pytest

from texelpad import cli
from texelpad.study import protocols
from texelpad.study.session import DataLock, DataLocked, Session


def _staircase(data, participant: str, n: int) -> Session:
    s = Session.create(data, "staircase", participant, {}, 4)
    for k in range(n):
        s.append({"answer": k % 2 == 0})
    return s


def test_a_record_after_a_last_line_without_newline_gets_its_own_line(tmp_path):
    s = _staircase(tmp_path, "p1", 3)
    s.path.write_bytes(s.path.read_bytes().rstrip(b"\n"))
    back = Session.open(s.path)
    assert len(back.records) == 3 and not back.torn        # the last record is whole: kept
    back.append({"answer": True})
    lines = s.path.read_bytes().split(b"\n")
    assert lines[-1] == b"" and len(lines) == 6
    again = Session.open(s.path)
    assert [r["answer"] for r in again.answers()] == [True, False, True, True]
    assert [r["n"] for r in again.records] == [0, 1, 2, 3]
    st = protocols.replay(again)
    assert len(st.track) == 4


def test_a_torn_last_line_is_still_cut_before_the_next_record(tmp_path):
    s = _staircase(tmp_path, "p1", 2)
    s.path.write_bytes(s.path.read_bytes() + b'{"kind":"answer","ans')
    back = Session.open(s.path)
    assert back.torn and len(back.records) == 2
    back.append({"answer": False})
    assert [r["answer"] for r in Session.open(s.path).answers()] == [True, False, False]


def test_export_leaves_a_broken_session_out_and_exports_the_rest(tmp_path, capsys):
    data = tmp_path / "data"
    _staircase(data, "p1", 3)
    bad = _staircase(data, "p2", 3)
    lines = bad.path.read_bytes().splitlines(keepends=True)
    lines[2] = lines[2][:-1] + lines[3]                # glued, as the old append did
    bad.path.write_bytes(b"".join(lines[:3] + lines[4:]))
    _staircase(data, "p3", 2)
    out = tmp_path / "out"
    code = cli.main(["lab", "export", "--data", str(data), "--out", str(out)])
    so, err = capsys.readouterr()
    assert code == 1 and "(5 answers) and 2 figures" in so, (so, err)
    assert "p2/staircase-1.jsonl: line 3 is damaged" in err and "1 of 3 sessions left out" in err
    assert "Traceback" not in err
    rows = list(csv.DictReader(open(out / "sessions.csv")))
    assert [r["participant"] for r in rows] == ["p1"] * 3 + ["p3"] * 2


def test_export_of_a_session_that_does_not_replay_names_it(tmp_path, capsys):
    data = tmp_path / "data"
    _staircase(data, "p1", 2)
    s = Session.create(data, "pursuit", "p2", {}, 1)
    s.append({"answer": "sideways"})                     # no answer a pursuit takes
    code = cli.main(["lab", "export", "--data", str(data), "--out", str(tmp_path / "o")])
    so, err = capsys.readouterr()
    assert code == 1 and "(2 answers)" in so and "p2/pursuit-1.jsonl: does not replay" in err


@pytest.mark.parametrize("what", ["missing", "empty", "file"])
def test_export_of_no_sessions_is_an_error_and_writes_nothing(tmp_path, capsys, what):
    data = tmp_path / "data"
    if what == "empty":
        data.mkdir()
    elif what == "file":
        data.write_text("x")
    out = tmp_path / "out"
    code = cli.main(["lab", "export", "--data", str(data), "--out", str(out)])
    so, err = capsys.readouterr()
    assert code == 1 and so == "" and not out.exists(), (so, err)
    assert len(err.strip().splitlines()) == 1 and "--data" in err
    assert {"missing": "no such folder", "empty": "no session files",
            "file": "not a folder"}[what] in err


def test_one_holder_per_data_folder_and_its_port_is_remembered(tmp_path):
    a = DataLock(tmp_path).acquire()
    a.update(http_port=43210)
    with pytest.raises(DataLocked, match="process %d on http://127.0.0.1:43210/" % os.getpid()):
        DataLock(tmp_path).acquire()
    # another process too (flock is per open file, and per process)
    code = ("import sys; from texelpad.study.session import DataLock\n"
            "try:\n DataLock(sys.argv[1]).acquire()\nexcept Exception as e:\n print(e); sys.exit(3)")
    p = subprocess.run([sys.executable, "-c", code, str(tmp_path)], capture_output=True,
                       text=True, timeout=60)
    assert p.returncode == 3 and "process %d" % os.getpid() in p.stdout, p
    a.release()
    b = DataLock(tmp_path).acquire()
    assert b.previous["http_port"] == 43210 and b.previous["pid"] == os.getpid()
    b.release()
    # a holder killed without letting go: the kernel drops the lock, the file says its port
    code = ("import os, sys; from texelpad.study.session import DataLock\n"
            "DataLock(sys.argv[1]).acquire().update(http_port=40001); os._exit(0)")
    subprocess.run([sys.executable, "-c", code, str(tmp_path)], check=True, timeout=60)
    c = DataLock(tmp_path).acquire()
    assert c.previous["http_port"] == 40001
    assert json.loads((tmp_path / DataLock.NAME).read_text())["pid"] == os.getpid()
    c.release()
