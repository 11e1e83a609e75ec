"""One rule for every input path (io/paths.py): names, file types and the text size cap (issue 25)."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from drive_envelope import InputError
from drive_envelope._src.cli.main import main
from drive_envelope._src.io import paths
from drive_envelope._src.io.files import read_mapping, read_text

GOOD = Path(__file__).resolve().parent / "corpus" / "good"


def test_a_text_input_over_the_cap_is_refused_by_its_size(tmp_path: Path) -> None:
    """Refuse a file larger than the cap before reading it, saying the cap; one at the cap is read."""
    file = tmp_path / "big.toml"
    file.write_text("a = 1\n" + "#" * 94 + "\n", encoding="utf-8")  # 101 bytes
    assert read_text(file).startswith("a = 1")
    with pytest.raises(
        InputError, match=r"big\.toml: is 101 bytes; a text input is read whole and may be at most 100 bytes"
    ):
        paths.read_input_bytes(file, max_bytes=100)
    assert paths.read_input_bytes(file, max_bytes=101)[:5] == b"a = 1"
    assert paths.MAX_TEXT_BYTES == 256 * 1024 * 1024


def test_a_file_that_reports_no_size_is_still_capped() -> None:
    """/proc files say 0 bytes: the read itself stops past the cap (a file growing while read too)."""
    status = Path("/proc/self/status")
    if not status.is_file():
        pytest.skip("needs /proc")
    assert os.stat(status).st_size == 0
    with pytest.raises(InputError, match="is larger than 10 bytes, the most a text input is read whole"):
        paths.read_input_bytes(status, max_bytes=10)


def test_fifo_and_device_inputs_are_refused_at_once(tmp_path: Path) -> None:
    """A FIFO without a writer and a link to /dev/zero are refused by type, without blocking or reading."""
    fifo = tmp_path / "envelope.toml"
    os.mkfifo(fifo)
    zero = tmp_path / "zero.json"
    zero.symlink_to("/dev/zero")
    start = time.monotonic()
    with pytest.raises(InputError, match=r"envelope\.toml: is a FIFO \(named pipe\), not a regular file"):
        read_mapping(fifo)
    with pytest.raises(InputError, match=r"zero\.json: is a character device, not a regular file"):
        read_mapping(zero)
    assert time.monotonic() - start < 5


def test_name_and_path_lengths(tmp_path: Path) -> None:
    """255 bytes per name and 4095 in all are allowed; one more is refused naming the length."""
    paths.check_path_name("a" * 255)
    paths.check_path_name("/".join(["b" * 200] * 20)[:4095])
    with pytest.raises(InputError, match="a name in this path is 256 bytes long"):
        paths.check_path_name(tmp_path / ("a" * 256))
    with pytest.raises(InputError, match="a name in this path is 258 bytes long"):
        paths.check_path_name("é" * 129)  # 2 bytes each in UTF-8: the limit is bytes, not characters
    with pytest.raises(InputError, match="the path is 4096 bytes long; expected at most 4095"):
        paths.check_path_name("/".join(["c" * 200] * 21)[:4096])


def test_non_utf8_text_names_the_byte_and_line(tmp_path: Path) -> None:
    """Say which byte on which line is not UTF-8 (never a UnicodeDecodeError)."""
    file = tmp_path / "latin.toml"
    file.write_bytes(b'a = 1\nname = "caf\xe9"\n')
    with pytest.raises(InputError, match=r"latin\.toml: cannot read: byte 0xe9 on line 2 is not UTF-8 text"):
        read_mapping(file)


@pytest.mark.parametrize(
    "argv",
    [
        ["simulate", str(GOOD / "scenario.toml"), "-o", "{out}/a/b/run.csv"],
        ["derive", "tmotor-ak80-6", "-o", "{out}/a/b/envelope.toml"],
        ["fit", str(GOOD / "sweep.csv"), "--bootstrap", "0", "-o", "{out}/a/b/fit.toml"],
    ],
    ids=["simulate", "derive", "fit"],
)
def test_outputs_create_missing_folders(argv: list[str], tmp_path: Path) -> None:
    """-o into folders that do not exist yet makes them and writes the file (issue 24)."""
    resolved = [a.replace("{out}", str(tmp_path)) for a in argv]
    assert main(resolved) == 0
    target = Path(resolved[-1])
    assert target.is_file() and target.stat().st_size > 0


def test_a_file_is_never_read_as_toml_by_guess(tmp_path: Path) -> None:
    sheet = tmp_path / "motor.txt"
    sheet.write_text('name = "x"\n')
    with pytest.raises(
        InputError, match=r"motor\.txt: expected a \.toml, \.json, \.yaml or \.yml file.*'\.txt'"
    ):
        read_mapping(sheet)


def test_load_envelope_of_a_catalog_name_points_to_the_resolver() -> None:
    from drive_envelope import load_envelope

    with pytest.raises(InputError, match=r"'tmotor-ak80-6': no such envelope file; .*resolve_envelope"):
        load_envelope("tmotor-ak80-6")
