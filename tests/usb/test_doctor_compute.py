"""``seecap doctor`` asks torch itself whether it can use a GPU, not only the driver."""

from davis_io.usb import doctor


def test_torch_is_asked_in_a_child_process_and_answers():
    usable, said = doctor._torch_cuda()
    assert said.startswith("torch ") and ("sees no CUDA device" in said) != usable


def test_a_driver_gpu_that_torch_cannot_use_is_a_failed_check(monkeypatch, tmp_path):
    (tmp_path / "0000:01:00.0").mkdir()
    monkeypatch.setattr(doctor, "_NVIDIA_GPUS", tmp_path)
    monkeypatch.setattr(
        doctor, "_torch_cuda", lambda: (False, "torch 2.13 (a CPU build) sees no CUDA device")
    )
    check = doctor._compute_check()
    assert not check.ok and "1 NVIDIA GPU(s) in the driver" in check.detail
    assert "install a CUDA build of torch" in check.detail
    monkeypatch.setattr(doctor, "_torch_cuda", lambda: (True, "torch 2.13 sees 1 CUDA device(s)"))
    assert doctor._compute_check().ok and "fitting uses the GPU" in doctor._compute_check().detail
