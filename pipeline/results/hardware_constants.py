r"""The hardware constants a designer can bring: every declared constant, a file's overrides.

The report's hardware figures rest on constants declared once where they are used, each with its
value, unit, meaning and source: the readout's power model
(:class:`pipeline.results.readout_constants.EnergyModel`, each field's
:class:`~pipeline.results.readout_constants.Parameter`), Pelgrom's coefficient (``A_VT``, beside
:data:`pipeline.results.matched_area.A_VT_V_M`) and the decoder's per-operation energies
(:class:`pipeline.results.decoder_energy.DecoderEnergyModel`, each operation a band whose low and
high ends are two constants, ``<operation>_low_j`` and ``<operation>_high_j``). :data:`DECLARED`
gathers them by name; the names and units of a constants file are derived from it, never listed
again.

A constants file (TOML) overrides any of them, each with the unit it is given in and where the
value comes from::

    [a_vt_v_m]
    value = 3.5
    unit = "mV um"                      # the declared unit (DECLARED[name].parameter.unit)
    source = "foundry X, 180 nm matching report, rev. 3"

    [event_energy_j]
    value = 4.0
    unit = "pJ per event"
    source = "our comparator, post-layout simulation"

Every problem is found at once and said in one line naming the file and the key
(:class:`~pipeline.errors.EskinError`, exit status 2): an unknown name, a table that is not
``{value, unit, source}``, a unit other than the declared one, a value that is not a number or
is negative (not above 0 for A_VT, not a whole number >= 1 for a count), an empty source, a band
whose low end exceeds its high end.

What uses them: only figures computed from the result cubes, never the simulation. No constant
enters a scene, a cache key or a cube: the readout's power and the matched area are priced from
a cube's rates and swept fields, the decoder's energy from its operation counts. The report
(``eskin report --constants FILE``) and the power estimate (``eskin power --constants FILE``)
take a file; a search's power, area and decoder-energy objectives
(:mod:`pipeline.results.objectives`) use the declared defaults.
"""

from __future__ import annotations

import dataclasses
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pipeline.errors import EskinError
from pipeline.results.decoder_energy import DECODER_OPERATIONS, DecoderEnergyModel, OperationEnergy
from pipeline.results.matched_area import A_VT, A_VT_V_M
from pipeline.results.readout_constants import PARAMETERS, EnergyModel, Parameter

__all__ = [
    "DECLARED",
    "FILE_KEYS",
    "Constants",
    "Declared",
    "Override",
    "load_constants",
]

#: The keys of one constant's table in a constants file.
FILE_KEYS = ("value", "unit", "source")

_PJ = 1e-12
_ENDS = {"low": "low_j", "high": "high_j"}
_END_SOURCES = {"low": "low_source", "high": "high_source"}


@dataclass(frozen=True)
class Declared:
    """One declared constant: its ``name`` (a constants file's key), its ``default`` in SI units
    and its :class:`~pipeline.results.readout_constants.Parameter` (unit, meaning, source)."""

    name: str
    default: float
    parameter: Parameter

    def in_unit(self, value: float) -> str:
        """``value`` (SI) in the declared unit, e.g. ``"5 mV um"``."""
        return f"{value / self.parameter.scale:.4g} {self.parameter.unit}"


def _declared() -> dict[str, Declared]:
    found = {
        name: Declared(name, getattr(EnergyModel(), name), parameter)
        for name, parameter in PARAMETERS.items()
    }
    found["a_vt_v_m"] = Declared("a_vt_v_m", A_VT_V_M, A_VT)
    decoder = DecoderEnergyModel()
    for operation in DECODER_OPERATIONS:
        band: OperationEnergy = getattr(decoder, operation)
        for end, attribute in _ENDS.items():
            name = f"{operation}_{end}_j"
            parameter = Parameter(
                "pJ per operation",
                _PJ,
                f"{band.what}, the {end} end of its band",
                getattr(band, _END_SOURCES[end]),
            )
            found[name] = Declared(name, getattr(band, attribute), parameter)
    return found


DECLARED: dict[str, Declared] = _declared()
"""Every hardware constant by name, in order the readout's power model (in
:class:`~pipeline.results.readout_constants.EnergyModel`'s field order), ``a_vt_v_m``, then the
decoder's operations, low and high end each."""


@dataclass(frozen=True)
class Override:
    """A constant's value in SI units and where it comes from."""

    value: float
    source: str


@dataclass(frozen=True)
class Constants:
    """The declared constants with a designer's overrides (by name, :data:`DECLARED`).

    ``origin`` says where the overrides come from (a file's path), for the report.

    Raises
    ------
    ValueError
        An override names no declared constant.
    """

    overrides: Mapping[str, Override] = field(default_factory=dict)
    origin: str = ""

    def __post_init__(self) -> None:
        unknown = sorted(set(self.overrides) - set(DECLARED))
        if unknown:
            raise ValueError(f"not declared constants: {', '.join(unknown)}")

    def value(self, name: str) -> float:
        """Constant ``name`` in SI units (its override, else its declared default)."""
        found = self.overrides.get(name)
        return DECLARED[name].default if found is None else found.value

    def source(self, name: str) -> str:
        """Where constant ``name``'s value comes from."""
        found = self.overrides.get(name)
        return DECLARED[name].parameter.source if found is None else found.source

    def overriding(self, name: str, value: float, source: str) -> Constants:
        """These constants with ``name`` set to ``value`` (SI) from ``source``."""
        return dataclasses.replace(
            self, overrides={**self.overrides, name: Override(value, source)}
        )

    @property
    def a_vt_v_m(self) -> float:
        """Pelgrom's coefficient A_VT in V m."""
        return self.value("a_vt_v_m")

    def energy_model(self) -> EnergyModel:
        """The readout's power model of these constants."""
        return EnergyModel(
            **{
                name: int(self.value(name)) if p.count else self.value(name)
                for name, p in PARAMETERS.items()
            }
        )

    def decoder_model(self) -> DecoderEnergyModel:
        """The decoder's per-operation energies of these constants, each end with its source."""
        default = DecoderEnergyModel()
        bands = {}
        for operation in DECODER_OPERATIONS:
            names = {end: f"{operation}_{end}_j" for end in _ENDS}
            bands[operation] = dataclasses.replace(
                getattr(default, operation),
                **{_ENDS[end]: self.value(n) for end, n in names.items()},
                **{_END_SOURCES[end]: self.source(n) for end, n in names.items()},
            )
        return DecoderEnergyModel(**bands)


def load_constants(path: str | Path) -> Constants:
    """The constants of a constants file (the TOML layout of the module docstring).

    Raises
    ------
    EskinError
        One line naming the file and every key with a problem.
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise _error(path, [f"cannot read file: {exc.strerror}"]) from None
    except UnicodeDecodeError as exc:
        raise _error(path, [f"not UTF-8 text (byte {exc.start})"]) from None
    except tomllib.TOMLDecodeError as exc:
        raise _error(path, [f"not valid TOML: {exc}"]) from None
    problems: list[str] = []
    constants = read_constants(data, str(path), problems)
    if problems:
        raise _error(path, problems)
    return constants


def read_constants(data: Mapping[str, Any], origin: str, problems: list[str]) -> Constants:
    """The constants of a constants file's ``data``; every problem appended to ``problems``,
    each naming its key."""
    overrides: dict[str, Override] = {}
    for name, table in data.items():
        declared = DECLARED.get(name)
        if declared is None:
            problems.append(f"{name}: unknown constant (known: {', '.join(DECLARED)})")
            continue
        override = _read_override(declared, table, problems)
        if override is not None:
            overrides[name] = override
    constants = Constants(overrides, origin)
    for operation in DECODER_OPERATIONS:
        low, high = (f"{operation}_{end}_j" for end in _ENDS)
        if {low, high} & set(overrides) and constants.value(low) > constants.value(high):
            problems.append(
                f"{low}: {DECLARED[low].in_unit(constants.value(low))} is above {high} "
                f"({DECLARED[high].in_unit(constants.value(high))})"
            )
    return constants


def _read_override(declared: Declared, table: Any, problems: list[str]) -> Override | None:
    name, parameter = declared.name, declared.parameter
    if not isinstance(table, Mapping):
        problems.append(
            f"{name}: expected a table {{ value, unit, source }}, got {table!r} "
            f"(e.g. {name} = {{ value = {declared.default / parameter.scale:g}, "
            f'unit = "{parameter.unit}", source = "..." }})'
        )
        return None
    count = len(problems)
    for key in table:
        if key not in FILE_KEYS:
            problems.append(f"{name}.{key}: unknown key (known: {', '.join(FILE_KEYS)})")
    missing = [key for key in FILE_KEYS if key not in table]
    if missing:
        problems.append(f"{name}: needs {', '.join(missing)}")
    value, unit, source = (table.get(key) for key in FILE_KEYS)
    if unit is not None and (not isinstance(unit, str) or unit.split() != parameter.unit.split()):
        problems.append(f"{name}.unit: {unit!r} is not its unit (give it in {parameter.unit})")
    if value is not None and (found := parameter.problem(value, f"{name}.value")) is not None:
        problems.append(found)
    if source is not None and not (isinstance(source, str) and source.strip()):
        problems.append(f"{name}.source: {source!r} is not a source (say where the value is from)")
    if len(problems) > count:
        return None
    return Override(
        int(value) if parameter.count else float(value * parameter.scale), source.strip()
    )


def _error(path: Path, problems: list[str]) -> EskinError:
    n = len(problems)
    head = f"invalid constants file {path}" + (f" ({n} problems)" if n > 1 else "")
    text = f"{head}: " + "; ".join(problems)
    return EskinError(text.replace("\r", "\\r").replace("\n", "\\n"))
