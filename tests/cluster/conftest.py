"""One local Ray instance per module."""

import faulthandler

import pytest


@pytest.fixture(scope="module")
def local_ray():
    """Ray on this machine with 2 CPUs, loopback only; the module dies after 15 minutes."""
    from seenerf.cli.cluster import ray_connection

    faulthandler.dump_traceback_later(900, exit=True)
    try:
        with ray_connection("local", cpus=2) as ray:
            yield ray
    finally:
        faulthandler.cancel_dump_traceback_later()
