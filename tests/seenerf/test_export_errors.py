"""An image a full disk did not take is an error naming the file, never a silent gap."""

import errno

import numpy as np
import OpenEXR
import pytest

from seenerf.eval import export


def test_a_png_opencv_did_not_write_is_an_error(tmp_path, monkeypatch):
    monkeypatch.setattr(export.cv2, "imwrite", lambda path, pixels: False)
    path = tmp_path / "renders" / "view.png"
    with pytest.raises(OSError, match="not written .*MB free.*seecap render") as caught:
        export.write_png(path, np.zeros((4, 5, 3)))
    assert caught.value.filename == str(path) and caught.value.errno == errno.EIO


def test_an_exr_openexr_could_not_write_is_an_error(tmp_path, monkeypatch):
    class FullDisk:
        def __init__(self, header, channels):
            pass

        def __enter__(self):
            raise RuntimeError("Error writing view.exr: No space left on device\nmore")

        def __exit__(self, *exc):
            return False

    monkeypatch.setattr(OpenEXR, "File", FullDisk)
    path = tmp_path / "view.exr"
    with pytest.raises(OSError, match="No space left on device; ") as caught:
        export.write_exr(path, np.zeros((4, 5, 3), np.float32), {})
    assert caught.value.filename == str(path)


def test_the_fit_verb_says_it_in_one_line(capsys):
    from davis_io.cli import _failure

    error = OSError(errno.ENOSPC, "not written (x; 0 MB free on its disk)", "r/view.png")
    assert _failure(error, "fit", debug=False) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "r/view.png" in err and "0 MB free" in err
