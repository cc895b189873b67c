import pytest

from davis_io.errors import UsageError
from davis_io.session.units import parse_duration_us


@pytest.mark.parametrize(
    ("text", "expected_us"),
    [
        ("0.15", 150_000),
        ("0.15s", 150_000),
        ("150ms", 150_000),
        ("150000us", 150_000),
        ("1e-3", 1_000),
        ("0.256", 256_000),
        ("2.5ms", 2_500),
        ("10m", 600_000_000),
        ("1.5min", 90_000_000),
        ("1.5h", 5_400_000_000),
    ],
)
def test_parse_duration_accepts_seconds_ms_us(text, expected_us):
    assert parse_duration_us(text) == expected_us


@pytest.mark.parametrize("text", ["", "fast", "-1", "0", "0.1d", "10mm", "0.0000001"])
def test_parse_duration_rejects_with_the_option_name(text):
    with pytest.raises(UsageError, match="--exposure"):
        parse_duration_us(text, what="--exposure")
