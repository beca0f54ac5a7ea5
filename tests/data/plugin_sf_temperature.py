"""A user's effect, in a plugin file: the scale factor follows the DTG's temperature.

Not part of gyrocal's library; the tests load it with ``plugins: [tests/data/plugin_sf_temperature.py]``
(the tutorial's copy is ``examples/temperature/plugin_sf_temperature.py``).
"""

import numpy as np

from gyrocal.model.effects import Effect, Parameter


class SfTemperature(Effect):
    name = "sf_temperature"
    description = "scale factor proportional to the DTG's temperature (gyro.csv columns temp_dtg<N>)"
    parameters = (Parameter("sf_per_kelvin", unit="ppm/K", si_per_unit=1e-6, prior_sd=500.0),)

    def gyro(self, m):
        temperature = np.column_stack([m.extras[f"temp_dtg{c.dtg}"] for c in m.channels])
        return {"sf_per_kelvin": temperature * m.increments}


EFFECTS = [SfTemperature()]
