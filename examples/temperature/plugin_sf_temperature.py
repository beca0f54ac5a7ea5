"""A user's effect, in a plugin file: the scale factor follows the DTG's temperature.

Not part of gyrocal's library; the tutorial loads it with
``plugins: [examples/temperature/plugin_sf_temperature.py]`` (``examples/temperature/config.yaml``).
"""

import numpy as np

from gyrocal.effects import Effect, Parameter


class SfTemperature(Effect):
    name = "sf_temperature"
    description = "scale factor proportional to the DTG's temperature (gyro.csv columns temp_dtg<N>)"
    parameters = (Parameter("sf_per_kelvin", unit="ppm/K", si_per_unit=1e-6, prior_sd=500.0),)

    def gyro(self, m):
        temperature = np.column_stack([m.extras[f"temp_dtg{c.dtg}"] for c in m.channels])
        return {"sf_per_kelvin": temperature * m.increments}


EFFECTS = [SfTemperature()]
