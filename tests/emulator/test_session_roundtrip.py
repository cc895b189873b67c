import h5py
import numpy as np

from davis_io.aedat import open_recording, write_aedat4
from davis_io.emulator import EmulatedCamera
from davis_io.session.recorder import record

SMALL = dict(width=64, height=48, focal_px=52.0, frames=2, test_views=1, exposure_us=20_000)


def datasets(path):
    found = {}
    with h5py.File(path, "r") as h5:
        h5.visititems(
            lambda name, item: (
                found.update({name: item[()]}) if isinstance(item, h5py.Dataset) else None
            )
        )
    return found


def test_replay_of_its_own_aedat4_records_the_same_session(tmp_path):
    emulated = record(EmulatedCamera("corridor", seed=2, **SMALL), tmp_path / "emulated")
    aedat = write_aedat4(EmulatedCamera("corridor", seed=2, **SMALL), tmp_path / "c.aedat4")
    replayed = record(open_recording(aedat), tmp_path / "replayed")
    assert emulated.status == replayed.status == "complete"
    ours = datasets(emulated.folder / "session.h5")
    theirs = datasets(replayed.folder / "session.h5")
    assert ours.keys() == theirs.keys()
    assert len(ours["events/t"]) > 1000 and len(ours["frames/image"]) == 2
    for name, values in ours.items():
        np.testing.assert_array_equal(theirs[name], values, err_msg=name)
