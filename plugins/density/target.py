"""A target packing fraction, porosity or void ratio, met by choosing eta (density ``target``).

What a lab specifies is a porosity, not a packing control coefficient. The
``target`` controller packs the scene with ``eta = 0`` (the densest it
gives) and with ``eta = eta_max`` (the loosest the search goes to), refuses
a target outside those two fractions (widened by the tolerance) with the
reachable range, and otherwise narrows the bracket by the Illinois variant
of regula falsi on the measured fraction until a packing is within the
tolerance or ``packings`` packings have been made. Every packing starts from
the scene's seed, so the packing kept is exactly the one ``density.kind =
"eta"`` with the chosen ``eta`` gives, and the same scene and seed choose the
same ``eta``.

The fraction measured is the interior one by default (inside the walls by
the run's interior margin, as the run's summary reports it), or the
domain's (``of = "domain"``). The fraction falls with ``eta`` but not
strictly (each eta draws its own trims): the bracket is kept by the
measured values, so the search ends inside it whatever the noise.

>>> ctl = TargetController(TargetConfig(porosity=0.25, tolerance=0.01))
>>> ctl.phi
0.75
>>> found = ctl.search(lambda c: 0.85 - 0.003 * c.eta)  # a made-up fraction of eta
>>> found.met, abs(found.tries[found.chosen]["phi"] - 0.75) <= 0.01
(True, True)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from typing import Literal, Self

from pydantic import BaseModel, ConfigDict, Field, model_validator

from regopack.base.field_error import FieldValueError
from regopack.plugins.density.eta import EtaConfig, EtaController
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import DensityController, DensitySearch, DensityTarget
from regopack.registry.plugin_types import DensityControllerSpec

__all__ = ["TargetConfig", "TargetController"]


class TargetConfig(BaseModel):
    """Parameters of the ``target`` controller: one of ``phi``, ``porosity``, ``void_ratio``."""

    model_config = ConfigDict(extra="forbid", strict=True)

    phi: float | None = Field(
        None,
        gt=0,
        lt=1,
        allow_inf_nan=False,
        description="Packing (solid) fraction to reach, between 0 and 1.",
    )
    porosity: float | None = Field(
        None,
        gt=0,
        lt=1,
        allow_inf_nan=False,
        description="Porosity to reach (1 - phi), between 0 and 1.",
    )
    void_ratio: float | None = Field(
        None,
        gt=0,
        le=1e6,
        allow_inf_nan=False,
        description="Void ratio to reach (pore over solid volume, phi = 1 / (1 + e)), above 0.",
    )
    of: Literal["interior", "domain"] = Field(
        "interior",
        description=(
            "Which fraction the target is about: inside the walls by the run's interior "
            "margin (as the summary's phi_interior), or of the whole domain."
        ),
    )
    tolerance: float = Field(
        0.002,
        gt=0,
        le=0.1,
        allow_inf_nan=False,
        description="How close to the target phi the packing kept must be (absolute, in phi).",
    )
    eta_max: float = Field(
        100.0,
        gt=0,
        le=1000,
        allow_inf_nan=False,
        description=(
            "Largest eta the search tries (the loosest end of the reachable range); "
            "past about 100 most particles find no room."
        ),
    )
    packings: int = Field(
        10,
        ge=2,
        le=100,
        strict=False,
        description="Most packings the search makes (each a full run of the scene).",
    )

    @model_validator(mode="after")
    def _one_target(self) -> Self:
        given = [n for n in ("phi", "porosity", "void_ratio") if getattr(self, n) is not None]
        if len(given) != 1:
            raise ValueError(
                "give exactly one of phi, porosity and void_ratio"
                + (f" (got {' and '.join(given)})" if given else "")
            )
        return self


class TargetController(DensityTarget):
    """Choose ``eta`` by packing until the scene's fraction is within the target's tolerance."""

    controls = "eta"

    def __init__(self, config: TargetConfig) -> None:
        self.config = config
        self.measure = config.of
        self.tolerance = config.tolerance
        if config.phi is not None:
            self.field, self.value, self.phi = "density.phi", config.phi, config.phi
        elif config.porosity is not None:
            self.field, self.value = "density.porosity", config.porosity
            self.phi = 1.0 - config.porosity
        else:
            assert config.void_ratio is not None
            self.field, self.value = "density.void_ratio", config.void_ratio
            self.phi = 1.0 / (1.0 + config.void_ratio)

    def _refuse(self, text: str) -> FieldValueError:
        return FieldValueError(self.field, self.value, text)

    def search(self, probe: Callable[[DensityController], float]) -> DensitySearch:
        """Bracket the target between ``eta = 0`` and ``eta_max``, then narrow the bracket."""
        cfg = self.config
        target, tol = self.phi, cfg.tolerance
        tries: list[dict[str, float]] = []

        def pack(eta: float) -> float:
            phi = float(probe(EtaController(EtaConfig(eta=eta))))
            tries.append({"eta": eta, "phi": phi})
            if math.isnan(phi):
                raise self._refuse(
                    f"the {self.measure} fraction cannot be measured on this scene (its "
                    'interior window is empty): set density.of = "domain" or a larger domain'
                )
            return phi

        def near(f: float) -> bool:  # within the tolerance, a rounding of it included
            return abs(f) <= tol + 1e-12

        def done(k: int) -> DensitySearch:
            return DensitySearch(k, tries, near(tries[k]["phi"] - target))

        what = f"phi {self.measure} {target:.4g}"
        a, fa = 0.0, pack(0.0) - target
        if near(fa):
            return done(0)
        if fa < 0.0:
            raise self._refuse(
                f"{what} is above the densest this scene packs, {tries[0]['phi']:.4f} at eta = 0"
            )
        b, fb = cfg.eta_max, pack(cfg.eta_max) - target
        if near(fb):
            return done(1)
        if fb > 0.0:
            raise self._refuse(
                f"{what} is below the loosest this search reaches, {tries[1]['phi']:.4f} at "
                f"eta = {cfg.eta_max:g} (density.eta_max); the reachable range is "
                f"{tries[1]['phi']:.4f} to {tries[0]['phi']:.4f}"
            )
        side = 0  # which end the last two steps kept (Illinois: halve the other's weight)
        while len(tries) < cfg.packings:
            eta = b - fb * (b - a) / (fb - fa)
            if not (a < eta < b):  # rounding at a bracket narrower than eta can resolve
                eta = 0.5 * (a + b)
            f = pack(eta) - target
            if near(f):
                return done(len(tries) - 1)
            if f > 0.0:  # still too dense: the root lies above eta
                a, fa = eta, f
                if side == -1:
                    fb *= 0.5
                side = -1
            else:
                b, fb = eta, f
                if side == 1:
                    fa *= 0.5
                side = 1
        best = min(range(len(tries)), key=lambda k: abs(tries[k]["phi"] - target))
        return done(best)


@hookimpl
def regopack_density_controllers() -> Iterable[DensityControllerSpec]:
    """Register the ``target`` density controller."""
    return [
        DensityControllerSpec(
            name="target",
            config_model=TargetConfig,
            factory=TargetController,
            description=(
                "A packing fraction, porosity or void ratio to reach: eta chosen by packing "
                "the scene until it is within the tolerance."
            ),
        )
    ]
