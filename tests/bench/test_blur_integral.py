from blur_integral import blur_model_psnr

from davis_io.emulator import EmulatedCamera
from davis_io.session.recorder import record

SMALL = dict(width=64, height=48, focal_px=52.0, frames=2, test_views=1, exposure_us=40_000)


def test_finer_blur_sums_come_closer_to_the_frames_than_the_latent_poses_alone(tmp_path):
    camera = EmulatedCamera("room", seed=1, **SMALL)
    session = record(camera, tmp_path / "s")
    camera.write_truth(session.folder)
    model, noise = blur_model_psnr(session.folder, b=2, per_bin=(1, 8), frames=2)
    # Three latent poses sum three sharp images; eight poses per bin nearly the emulator's 17.
    assert model[8] > model[1] + 5.0
    assert model[8] > 40.0
    assert 20.0 < noise < 60.0
