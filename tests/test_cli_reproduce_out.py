"""``hybridpd reproduce --out PATH`` refuses, in one line and with status 2 before anything
is computed, a PATH that is an existing file or where no directory can be written."""
import pytest

from hybridpd.cli import main


@pytest.mark.parametrize("where", ["file", "under_file", "file_in_dir"])
def test_reproduce_out_that_cannot_be_written(tmp_path, capsys, where):
    f = tmp_path / "taken.txt"
    f.write_text("not a directory\n", encoding="utf-8")
    out = {"file": f, "under_file": f / "sub", "file_in_dir": f / "a" / "b"}[where]
    rc = main(["reproduce", "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("hybridpd: error: --out ")
    assert "Traceback" not in err and f.read_text(encoding="utf-8") == "not a directory\n"
    assert ("existing file" in lines[0]) == (where == "file")
