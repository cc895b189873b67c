"""What the word decoder and encoder must know about a sensor: sizes, orientation, IMU type."""

from __future__ import annotations

from dataclasses import dataclass

from davis_io.chips import SENSOR_SIZES

__all__ = ["SensorLayout"]

_DEFAULT_COLUMNS, _DEFAULT_ROWS = SENSOR_SIZES["DAVIS346"]


@dataclass(frozen=True)
class SensorLayout:
    """Geometry and orientation of one DAVIS sensor, as read from its info registers.

    The defaults describe a DAVIS346 in its normal orientation.

    Attributes:
        dvs_columns: DVS SIZE_COLUMNS (raw, before invertXY), pixels.
        dvs_rows: DVS SIZE_ROWS (raw), pixels.
        dvs_invert_xy: DVS ORIENTATION_INFO bit 2 (swap row and column when decoding).
        aps_columns: APS SIZE_COLUMNS (raw), pixels.
        aps_rows: APS SIZE_ROWS (raw), pixels.
        aps_orientation: APS ORIENTATION_INFO (bit 2 invertXY, bit 1 flipX, bit 0 flipY).
        imu_type: IMU TYPE (0 none, 1 MPU-6050/6150, 2 MPU-9250).
        imu_orientation: IMU ORIENTATION_INFO (bit 2 flipX, bit 1 flipY, bit 0 flipZ).
        adc_doubling: True on DAVIS240, whose APS samples are doubled before CDS.
    """

    dvs_columns: int = _DEFAULT_COLUMNS
    dvs_rows: int = _DEFAULT_ROWS
    dvs_invert_xy: bool = False
    aps_columns: int = _DEFAULT_COLUMNS
    aps_rows: int = _DEFAULT_ROWS
    aps_orientation: int = 0
    imu_type: int = 1
    imu_orientation: int = 0
    adc_doubling: bool = False

    @property
    def aps_invert_xy(self) -> bool:
        """APS invertXY: readout columns run along image rows."""
        return bool(self.aps_orientation & 0b100)

    @property
    def aps_flip_x(self) -> bool:
        """APS flipX: readout column order is mirrored."""
        return bool(self.aps_orientation & 0b010)

    @property
    def aps_flip_y(self) -> bool:
        """APS flipY: sample order within a column is mirrored."""
        return bool(self.aps_orientation & 0b001)

    @property
    def width(self) -> int:
        """Image width in pixels after invertXY."""
        return self.dvs_rows if self.dvs_invert_xy else self.dvs_columns

    @property
    def height(self) -> int:
        """Image height in pixels after invertXY."""
        return self.dvs_columns if self.dvs_invert_xy else self.dvs_rows

    @property
    def imu_axis_signs(self) -> tuple[int, int, int]:
        """Sign applied to the raw x, y, z axis values (-1 where the flip bit is set)."""
        bits = (0b100, 0b010, 0b001)
        return tuple(-1 if self.imu_orientation & bit else 1 for bit in bits)
