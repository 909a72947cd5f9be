"""envconv.io.chatter: what image libraries print is captured, folded into errors, restored."""

from __future__ import annotations

import logging
import os
import warnings

import pytest

from envconv.errors import ImageIOError, UsageError
from envconv.io import chatter
from envconv.io.chatter import library_output, meaningful_lines


@pytest.fixture(autouse=True)
def captured():
    """Captures redirect only where the command line turned them on: these tests are about
    what it then catches (test_library_calls_leave_the_descriptors_alone is about the rest)."""
    previous = chatter.capture_descriptors(True)
    yield
    chatter.capture_descriptors(previous)


def test_descriptor_output_is_caught_and_logged_at_debug(capfd, caplog):
    """Writes to descriptors 1 and 2 (as C++ code makes them) never reach them; they are
    logged at debug level, once each, and the descriptors work again afterwards."""
    with caplog.at_level(logging.DEBUG, logger="envconv.io.chatter"):
        with library_output("cannot read a.exr", "a.exr") as caught:
            os.write(1, b"a.exr: chunk 3 is bad\n")
            os.write(2, b"a.exr: chunk 3 is bad\nWarning: second thing\n")
            print("through python")
    os.write(1, b"after\n")
    out, err = capfd.readouterr()
    assert out == "after\n" and err == ""
    assert caught.lines("a.exr") == ["chunk 3 is bad", "second thing", "through python"]
    assert [r.getMessage() for r in caplog.records] == [
        "library: chunk 3 is bad",
        "library: second thing",
        "library: through python",
    ]


def test_an_error_gets_the_first_new_line_and_keeps_its_type(capfd):
    with pytest.raises(ImageIOError) as info:
        with library_output("cannot read a.exr", "/some/dir/a.exr"):
            os.write(2, b"a.exr: (EXR_ERR_BAD_CHUNK_LEADER) corrupt leader\n" * 8)
            raise ImageIOError("cannot read a.exr: Some scanline chunks were missing")
    assert str(info.value) == ("cannot read a.exr: Some scanline chunks were missing; "
                               "(EXR_ERR_BAD_CHUNK_LEADER) corrupt leader")  # fmt: skip
    with pytest.raises(UsageError) as info:  # a line the message already holds is not repeated
        with library_output("cannot write b.exr"):
            os.write(2, b"no such layout\n")
            raise UsageError("no such layout")
    assert str(info.value) == "no such layout"
    assert capfd.readouterr() == ("", "")


def test_memory_error_becomes_a_one_line_io_error_and_other_errors_pass(capfd):
    with pytest.raises(ImageIOError, match="^cannot read big.exr: out of memory$"):
        with library_output("cannot read big.exr"):
            raise MemoryError("std::bad_alloc")
    with pytest.raises(KeyError):
        with library_output("cannot read c.exr"):
            raise KeyError("x")
    with pytest.raises(ZeroDivisionError):
        with library_output("cannot read c.exr"):
            os.write(1, b"noise\n")
            1 / 0  # noqa: B018
    assert capfd.readouterr() == ("", "")


def test_nested_captures_and_python_warnings(capfd):
    with library_output("outer") as outer:
        with library_output("inner") as inner:
            os.write(2, b"from C\n")
            warnings.warn("numpy says so", RuntimeWarning, stacklevel=1)
        os.write(2, b"outer only\n")
    assert capfd.readouterr() == ("", "")
    assert "RuntimeWarning: numpy says so" in outer.lines() + inner.lines()
    assert "from C" in outer.lines() + inner.lines()
    assert "outer only" in outer.lines()


def test_meaningful_lines_drop_prefixes_blanks_and_repeats():
    text = "x.exr: bad\n\n  x.exr: bad  \nWarning: Exception raised\nother\n"
    assert meaningful_lines(text, "x.exr") == ["bad", "Exception raised", "other"]
    assert meaningful_lines("/d/x.exr: bad\nx.exr: bad\n", "/d/x.exr") == [
        "bad"
    ]  # as given, or base


def test_envconv_log_lines_printed_meanwhile_pass_through(capfd):
    """The CLI's log handler writes to descriptor 2: a warning logged during a read is not
    taken for library output (nor demoted to debug)."""
    with library_output("cannot read a.exr") as caught:
        os.write(2, b"envconv: warning: part B is not read\nlibrary noise\n")
    assert capfd.readouterr() == ("", "envconv: warning: part B is not read\n")
    assert caught.lines() == ["library noise"]


def test_captures_in_two_threads_leave_the_streams_as_they_were(capfd):
    """Threads share the process's descriptors and sys.stdout: however two captures
    interleave, both are put back (a dask worker runs tasks on several threads)."""
    import sys
    import threading

    stdout, stderr = sys.stdout, sys.stderr
    inside, leave = threading.Event(), threading.Event()

    def other():
        with library_output("b"):
            inside.set()
            leave.wait(5)

    thread = threading.Thread(target=other)
    with library_output("a"):
        thread.start()
        assert inside.wait(5)
    leave.set()  # the first capture ended before the second
    thread.join(5)
    assert (sys.stdout, sys.stderr) == (stdout, stderr)
    os.write(1, b"out\n")
    print("printed")
    assert capfd.readouterr().out == "out\nprinted\n"
