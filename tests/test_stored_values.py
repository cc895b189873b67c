"""Values read back from ``config.json`` and ``session.json`` pass the same checks as options."""

import dataclasses
import json
import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from davis_io.errors import SessionError
from davis_io.session.manifest import MANIFEST_NAME, SessionManifest, read_manifest
from seenerf.errors import ConfigError, OptionError
from seenerf.model.config import FIELD_BOUNDS, FitConfig, load_config, save_config

HOSTILE = st.one_of(
    st.sampled_from([math.nan, math.inf, -math.inf, -1, 0, -0.5, 1e300, 10**30, True, None]),
    st.sampled_from(["", "nan", "fast", [], {}, [1, 2]]),
    st.integers(-(2**63), 2**63),
    st.floats(allow_nan=True, allow_infinity=True),
)


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("anchor_weight", math.nan, "--anchor-weight nan is out of range"),
        ("time_budget_s", math.inf, "--time-budget inf is out of range"),
        ("steps", -3, "--steps -3 is out of range"),
        ("batch_pixels", 10**9, "--batch-pixels 1000000000 is out of range"),
        ("steps", 2.5, "--steps 2.5 is out of range: give a whole number"),
        ("seed", True, "--seed True is out of range"),
        ("dead_time", "yes", "dead_time 'yes' must be true or false"),
        ("preset", "turbo", "preset 'turbo' is unknown"),
    ],
)
def test_a_bad_value_in_a_saved_config_is_a_usage_error_naming_it(tmp_path, field, value, message):
    path = tmp_path / "config.json"
    save_config(FitConfig(), path)
    payload = json.loads(path.read_text())
    (group,) = (group for group in payload["config"].values() if field in group)
    group[field] = value
    path.write_text(json.dumps(payload))
    with pytest.raises(OptionError, match=message) as refused:
        load_config(path)
    assert refused.value.exit_status == 2 and str(path) in str(refused.value)


def test_a_flat_config_of_an_older_run_reads_back_its_not_given_values_as_none(tmp_path):
    path = tmp_path / "config.json"
    flat = {"preset": "balanced", "steps": 0, "warm_steps": -1, "threshold": 0.0}
    flat |= {"event_weight": 0.002, "bins": 0, "threads": 3, "exposures_s": [0.01, 0.1]}
    path.write_text(json.dumps({"config": flat, "bins": 4}))
    config = load_config(path)
    assert config.model == dataclasses.replace(config.model, preset="balanced", event_weight=0.002)
    assert (config.schedule.steps, config.schedule.warm_steps, config.schedule.threads) == (
        None,
        None,
        3,
    )
    assert (config.sensor.threshold, config.data.bins) == (None, None)
    assert config.output.exposures_s == (0.01, 0.1)
    assert config.replaced(preset="fast") == FitConfig.of(
        event_weight=0.002, threads=3, exposures_s=(0.01, 0.1)
    )


@settings(max_examples=300, deadline=None, derandomize=True)
@given(st.sampled_from(sorted(FIELD_BOUNDS)), HOSTILE)
def test_any_value_of_a_config_field_is_taken_or_refused_by_name(field, value):
    try:
        config = FitConfig.of(**{field: value})
    except ConfigError as error:
        assert "--" + field.removesuffix("_s").replace("_", "-") in str(error)
    else:
        taken = config.options()[field]
        left_open = taken is None and FitConfig().options()[field] is None
        assert left_open or FIELD_BOUNDS[field].holds(taken)


@pytest.fixture
def manifest_folder(tmp_path):
    manifest = SessionManifest(
        camera="DAVIS346", serial="1", width=346, height=260, color_filter="mono", source="usb", b=4
    )
    (tmp_path / MANIFEST_NAME).write_text(manifest.to_json())
    return tmp_path


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("color_filter", "XYZW", "field 'color_filter' 'XYZW' is not one of"),
        ("b", 10**6, "field 'b' 1000000 is out of range: give a whole number from 1 to 64"),
        ("height", 10**6, "field 'height' 1000000 is out of range"),
        ("event_count", -1, "field 'event_count' -1 is out of range"),
        ("exposure_measured_us", -5, "field 'exposure_measured_us' -5 is out of range"),
    ],
)
def test_a_bad_value_in_session_json_is_named(manifest_folder, field, value, message):
    path = manifest_folder / MANIFEST_NAME
    payload = json.loads(path.read_text())
    payload[field] = value
    path.write_text(json.dumps(payload))
    with pytest.raises(SessionError, match=message):
        read_manifest(manifest_folder)


NUMERIC = [f.name for f in dataclasses.fields(SessionManifest) if f.type in ("int", "int | None")]


@settings(
    max_examples=300,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(st.sampled_from(NUMERIC + ["color_filter", "status", "drops"]), HOSTILE)
def test_any_value_of_a_manifest_field_is_read_or_refused_by_name(manifest_folder, field, value):
    path = manifest_folder / MANIFEST_NAME
    payload = json.loads(SessionManifest.from_json(path.read_text()).to_json())
    payload[field] = value
    text = json.dumps(payload)  # NaN and infinities as JSON's extensions, as a damaged file has
    try:
        SessionManifest.from_json(text)
    except SessionError as error:
        assert field in str(error) or field.replace("_", " ") in str(error)
