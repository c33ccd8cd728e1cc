"""The hypothesis profiles of the build properties (tests/conftest.py says how
TEXELPAD_HYPOTHESIS picks one): imported by the modules that use them."""
from hypothesis import HealthCheck, settings

NIGHTLY_SCALE = 25
_COMMON = dict(database=None, deadline=None, print_blob=True,
               suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                      HealthCheck.filter_too_much,
                                      HealthCheck.large_base_example])
settings.register_profile("texelpad-default", derandomize=True, **_COMMON)
settings.register_profile("texelpad-nightly", derandomize=False, **_COMMON)
