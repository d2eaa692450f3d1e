"""tapp.io.outputs: outputs never clobber inputs; a command's outputs are written all or none."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import pytest

from tapp.errors import InputError, WriteError
from tapp.io.atomic import atomic_write
from tapp.io.outputs import (
    OutputSet,
    check_paths,
    remove_stale_temporaries,
    stale_temporaries,
    temporary_name,
    unwritable,
)


def test_an_output_equal_to_an_input_is_refused_naming_both_options(tmp_path: Path) -> None:
    scenario = tmp_path / "S.toml"
    scenario.write_text("x = 1\n")
    with pytest.raises(InputError, match=r"^-o/--output: .*S.toml: expected a file other than "
                       r"the input SCENARIO"):
        check_paths({"SCENARIO": scenario}, {"-o/--output": scenario, "--oem": None})


@pytest.mark.parametrize("spelling", ["relative", "dotdot", "symlink", "hardlink"])
def test_every_spelling_of_the_same_file_is_caught(tmp_path: Path, monkeypatch,
                                                   spelling: str) -> None:
    scenario = tmp_path / "S.toml"
    scenario.write_text("x = 1\n")
    (tmp_path / "sub").mkdir()
    monkeypatch.chdir(tmp_path / "sub")
    if spelling == "relative":
        out = Path("../S.toml")
    elif spelling == "dotdot":
        out = tmp_path / "sub" / ".." / "S.toml"
    elif spelling == "symlink":
        out = tmp_path / "link.toml"
        out.symlink_to(scenario)
    else:
        out = tmp_path / "hard.toml"
        os.link(scenario, out)
    with pytest.raises(InputError, match="the input SCENARIO"):
        check_paths({"SCENARIO": scenario}, {"-o/--output": out})


def test_two_outputs_on_one_file_are_refused(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"^--oem: .*expected a file other than the output "
                       r"-o/--output"):
        check_paths({}, {"-o/--output": tmp_path / "a.h5", "--oem": tmp_path / "." / "a.h5"})


def test_unwritable_outputs_are_refused_before_any_work(tmp_path: Path) -> None:
    (tmp_path / "a_file").write_text("")
    with pytest.raises(InputError, match="^--csv: .*expected a path inside a folder"):
        check_paths({}, {"--csv": tmp_path / "a_file" / "out.csv"})
    with pytest.raises(InputError, match="^-o/--output: .*expected a file path, not a folder"):
        check_paths({}, {"-o/--output": tmp_path})
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    if os.access(locked, os.W_OK):  # root ignores permissions
        pytest.skip("running as root")
    with pytest.raises(InputError, match="^--save-obs: .*writable folder"):
        check_paths({}, {"--save-obs": locked / "obs.h5"})


def test_a_failed_write_leaves_every_old_output_and_no_temporary(tmp_path: Path) -> None:
    tape, oem = tmp_path / "run.t13.h5", tmp_path / "run.oem"
    tape.write_text("old tape")
    oem.write_text("old oem")

    def broken(tmp: Path) -> None:
        tmp.write_text("half a tape")
        raise RuntimeError("disk on fire")

    outputs = OutputSet()
    outputs.add("--oem", oem, lambda tmp: tmp.write_text("new oem"))
    outputs.add("-o/--output", tape, broken)
    with pytest.raises(RuntimeError, match="disk on fire"):
        outputs.commit()
    assert (tape.read_text(), oem.read_text()) == ("old tape", "old oem")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.oem", "run.t13.h5"]


def test_what_fails_between_writing_and_renaming_leaves_every_old_output(
        tmp_path: Path) -> None:
    """The block of ``staged`` (a command's report on standard output) fails after every
    temporary is complete: no output is replaced or made, no temporary and no folder made
    is left (issue 28: ``tapp simulate -o p.t13.h5 | head -1`` left p.t13.h5)."""
    tape, oem = tmp_path / "run.t13.h5", tmp_path / "new" / "run.oem"
    tape.write_text("old tape")
    outputs = OutputSet()
    outputs.add("-o/--output", tape, lambda tmp: tmp.write_text("new tape"))
    outputs.add("--oem", oem, lambda tmp: tmp.write_text("new oem"))
    with pytest.raises(BrokenPipeError), outputs.staged() as paths:
        assert paths == (tape, oem) and tape.read_text() == "old tape"
        raise BrokenPipeError(errno.EPIPE, "Broken pipe")  # an OSError, yet not an output's
    assert tape.read_text() == "old tape"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.t13.h5"]


def test_os_errors_name_the_requested_path_and_option_not_the_temporary(tmp_path: Path) -> None:
    def unwritable(tmp: Path) -> None:
        raise PermissionError(13, "Permission denied", str(tmp))

    outputs = OutputSet()
    outputs.add("--oem", tmp_path / "run.oem", unwritable)
    with pytest.raises(InputError) as info:
        outputs.commit()
    assert str(info.value) == (f"--oem: {tmp_path / 'run.oem'}: expected a writable file "
                               "(got 'Permission denied')")
    assert ".tmp" not in str(info.value)


def test_stale_temporaries_of_a_killed_run_are_removed_on_the_next_write(tmp_path: Path) -> None:
    target = tmp_path / "run.t13.h5"
    stale = [temporary_name(target), tmp_path / ".run.t13.h5.abcd1234.tmp",
             tmp_path / f".{temporary_name(target).name}.0123456789abcdef.tmp"]
    other = tmp_path / ".run.t13.h5.old.0123456789abcdef.tmp"  # another target's
    for path in (*stale, other):
        path.write_text("left by a kill")
    assert stale_temporaries(target) == sorted(stale)
    atomic_write(target, lambda tmp: tmp.write_text("new"))
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([other.name, target.name])


def test_a_killed_pipeline_s_hidden_folders_are_removed_whole_on_the_next_write(
        tmp_path: Path) -> None:
    target = tmp_path / "out"
    stale = [temporary_name(target), tmp_path / ".out.tmp-k2j4_x9q"]  # now, and before
    for folder in stale:
        (folder / "plots").mkdir(parents=True)
        (folder / "run.t13.h5").write_text("left by a kill")
    other = tmp_path / ".outer.0123456789abcdef.tmp"  # another target's
    other.mkdir()
    assert stale_temporaries(target) == sorted(stale)
    remove_stale_temporaries(target)
    assert sorted(p.name for p in tmp_path.iterdir()) == [other.name]


def test_a_failed_write_leaves_no_folder_it_made(tmp_path: Path) -> None:
    (tmp_path / "a").mkdir()  # there before: kept

    def no_space(tmp: Path) -> None:
        tmp.write_text("half")
        raise OSError(errno.ENOSPC, "No space left on device")

    outputs = OutputSet()
    outputs.add("--oem", tmp_path / "a" / "b" / "c" / "run.oem", lambda tmp: tmp.write_text("x"))
    outputs.add("-o/--output", tmp_path / "a" / "b" / "d" / "run.h5", no_space)
    with pytest.raises(WriteError) as info:
        outputs.commit()
    assert str(info.value) == (f"-o/--output: {tmp_path / 'a' / 'b' / 'd' / 'run.h5'}: not "
                               "written (No space left on device)")
    assert [p.relative_to(tmp_path) for p in tmp_path.rglob("*")] == [Path("a")]


@pytest.mark.parametrize(("code", "error"), [
    (errno.ENOSPC, WriteError), (errno.EDQUOT, WriteError), (errno.EIO, WriteError),
    (errno.EACCES, InputError), (errno.EROFS, InputError), (errno.EPERM, InputError),
    (errno.ENOTDIR, InputError),
])
def test_a_full_disk_is_the_machine_s_failure_and_a_read_only_folder_the_input_s(
        tmp_path: Path, code: int, error: type) -> None:
    made = unwritable("--tape", tmp_path / "run.t32.h5", OSError(code, os.strerror(code)))
    assert type(made) is error
    assert str(made).startswith(f"--tape: {tmp_path / 'run.t32.h5'}: ")
    assert os.strerror(code) in str(made)


def test_a_pipe_or_device_is_written_into_never_replaced(tmp_path):
    """``--json /dev/null`` run as root renamed a regular file over the machine's /dev/null:
    an output that names a device or a pipe is written into it (last), and stays what it
    is; the other outputs of the set are still renamed into place."""
    import os
    import stat
    import threading

    from tapp.io.outputs import OutputSet, check_writable, written_in_place

    fifo, plain = tmp_path / "fifo", tmp_path / "plain.txt"
    os.mkfifo(fifo)
    assert written_in_place(fifo) and not written_in_place(plain)
    check_writable("--json", fifo)  # no writable folder needed, the pipe itself is
    received: list[str] = []
    reader = threading.Thread(target=lambda: received.append(fifo.read_text()))
    reader.start()
    outputs = OutputSet()
    outputs.add("--json", fifo, lambda p: p.write_text('{"a": 1}'))
    outputs.add("-o", plain, lambda p: p.write_text("plain"))
    assert outputs.commit() == (fifo, plain)
    reader.join(timeout=10)
    assert received == ['{"a": 1}']
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert plain.read_text() == "plain"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fifo", "plain.txt"]
