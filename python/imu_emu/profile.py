"""Sensor profile files (``imu-emu --sensor-profile FILE``): read one, with
the datasheet figures derived from it.

A profile is TOML (``imu-emu sensor-profile show K110`` prints a built-in
one): sections ``gyro``, ``acc`` and, for a unit with an aux
accelerometer (K120, K220), ``aux``, with the keys of :data:`SENSOR_KEYS`
(gyro in deg/s, accelerometers in g) and ``temperature`` with
:data:`TEMPERATURE_KEYS`; every key of a section is required
(docs/sensors.md). A file without ``aux`` keeps the unit's built-in aux
figures in the emulator; here it has no ``aux`` entry. The TOML reader is the standard library's ``tomllib``
on Python 3.11 and later, and ``tomli`` (the same API; a dependency the
package declares for older Pythons only) before.
"""

import sys

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on the oldest Python CI tests
    import tomli as tomllib

#: g in m/s^2 (ICD Table 5.5 note 1), as the emulator uses it.
G = 9.8106

SENSOR_KEYS = (
    "range", "noise_density", "bias_instability", "rate_random_walk",
    "turn_on_bias_sigma", "scale_factor_sigma", "nonlinearity",
    "misalignment_sigma", "g_sensitivity", "temp_bias", "temp_scale",
    "resolution", "bandwidth_hz",
)
TEMPERATURE_KEYS = ("ambient_c", "self_heating_c", "time_constant_s")


class ProfileError(ValueError):
    """A profile file that is not one (the message names the key)."""


def read_profile(path):
    """The profile in ``path`` as a dict of sections (``gyro``, ``acc``,
    ``aux`` when the file has one: dicts of :data:`SENSOR_KEYS`; ``temperature``), each sensor
    with its datasheet figures added under ``datasheet``: gyro ``arw_deg_rt_h``
    and ``bias_instability_deg_h``; accelerometers ``vrw_m_s_rt_h`` and
    ``bias_instability_ug``. Raises :class:`ProfileError` naming a missing
    or unknown key. (The allowed ranges are checked by the emulator:
    ``imu-emu sensor-profile check FILE``.)"""
    with open(path, "rb") as f:
        data = tomllib.load(f)
    out = {}
    for section, keys in (("gyro", SENSOR_KEYS), ("acc", SENSOR_KEYS),
                          ("aux", SENSOR_KEYS), ("temperature", TEMPERATURE_KEYS)):
        table = data.get(section)
        if section == "aux" and table is None:
            continue
        if not isinstance(table, dict):
            raise ProfileError(f"{path}: missing section [{section}]")
        for k in table:
            if k not in keys:
                raise ProfileError(f"{path}: unknown key {section}.{k}")
        for k in keys:
            if k not in table:
                raise ProfileError(f"{path}: missing key {section}.{k}")
            if not isinstance(table[k], (int, float)):
                raise ProfileError(f"{path}: {section}.{k} is not a number")
        out[section] = {k: float(table[k]) for k in keys}
    for k in data:
        if k not in out:
            raise ProfileError(f"{path}: unknown section [{k}]")
    g = out["gyro"]
    g["datasheet"] = {
        "arw_deg_rt_h": g["noise_density"] * 60.0,
        "bias_instability_deg_h": g["bias_instability"] * 3600.0,
    }
    for s in ("acc", "aux"):
        if s not in out:
            continue
        a = out[s]
        a["datasheet"] = {
            "vrw_m_s_rt_h": a["noise_density"] * 60.0 * G,
            "bias_instability_ug": a["bias_instability"] * 1e6,
        }
    return out
