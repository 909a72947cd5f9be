"""A signal that lands just as a temporary file is made leaves nothing behind (issue 27).

The hostile suite's ``test_sigterm_during_a_large_write`` sends SIGTERM the moment a temp
appears; on a loaded machine the handler's exception (envconv.engine.interrupt) was raised in
the few bytecodes between the file's creation and its registration, or between its return and
its writer's list, and the run exited 143 with the temp left in the output folder. These tests
put the exception exactly there, deterministically.
"""

from __future__ import annotations

import os
import signal

import pytest

from envconv.cli.main import _interrupted
from envconv.engine.interrupt import Interrupted, remove_live_temps
from envconv.io import output, temps


def _litter(folder) -> list[str]:
    return [name for name in os.listdir(folder) if temps.is_temp_name(name)]


def test_a_temp_is_live_from_before_it_exists(tmp_path, monkeypatch):
    """The signal lands right after ``os.open`` made the file: it is already among this
    process's live temps, which the interrupted run removes."""
    real_open = os.open

    def open_then_signal(path, flags, mode=0o777):
        fd = real_open(path, flags, mode)
        os.close(fd)
        raise Interrupted(signal.SIGTERM)

    monkeypatch.setattr(temps.os, "open", open_then_signal)
    with pytest.raises(Interrupted):
        temps.temp_path(str(tmp_path / "out.exr"))
    monkeypatch.undo()
    (made,) = _litter(tmp_path)
    assert str(tmp_path / made) in temps.live_temps()
    remove_live_temps()
    assert _litter(tmp_path) == [] and temps.live_temps() == []


def test_a_signal_between_a_temp_and_its_writer_is_cleaned_at_the_command_line(
    tmp_path, monkeypatch
):
    """The signal lands after the temp was made but before write_files holds it: the command
    line's handler of the interruption removes it, exits 143 and leaves the target alone."""
    real_temp_for = output.temp_for

    def temp_then_signal(target, token=None):
        real_temp_for(target, token)
        raise Interrupted(signal.SIGTERM)

    monkeypatch.setattr(output, "temp_for", temp_then_signal)
    target = tmp_path / "out.exr"
    target.write_bytes(b"old")
    with pytest.raises(Interrupted) as caught:
        output.write_files([str(target)], lambda temp, target, index: None)
    assert len(_litter(tmp_path)) == 1
    with pytest.raises(SystemExit) as exited:
        _interrupted(caught.value)
    assert exited.value.code == 143
    assert _litter(tmp_path) == [] and temps.live_temps() == []
    assert target.read_bytes() == b"old"
