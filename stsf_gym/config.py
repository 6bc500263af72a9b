"""Configuration entry points for users of the library (the schema lives in
``stsf_gym.envs.config``)."""

from stsf_gym.envs.config import CONFIG_DIR, EnvConfig, load_config
from stsf_gym.validation import ConfigError

__all__ = ["CONFIG_DIR", "EnvConfig", "load_config", "parse_overrides"]


def parse_overrides(items: list[str]) -> dict:
    """``["camera.width=640", "world=straight_10m"]`` to overrides; values parsed as YAML
    (:func:`~stsf_gym.config_files.load_value`: ``1e-4`` is a number). A key given twice is
    refused, as in a config file: only one of the two could hold."""
    import yaml

    from stsf_gym.config_files import load_value

    overrides: dict = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ConfigError(f"override {item!r} must look like section.key=value")
        try:
            parsed = load_value(value)
        except yaml.YAMLError as err:
            problem = getattr(err, "problem", None) or str(err)
            raise ConfigError(f"override {item!r}: {problem}", key.strip()) from err
        if key.strip() in overrides:
            raise ConfigError(
                f"override {key.strip()!r} is given twice ({overrides[key.strip()]!r}, then "
                f"{parsed!r}); only one could hold: give it once",
                key.strip(),
            )
        overrides[key.strip()] = parsed
    return overrides
