"""Table 2 of the continuous-connectivity paper: the radii and lambda2 thresholds.

Continuous-connectivity paper (Nestmeyer et al., "Decentralized simultaneous
multi-target exploration using a connected network of multiple robots"),
Sec. 2 and Appendix A, after Robuffo Giordano et al. (2013).

``TABLE2`` holds the paper's three columns (empty space and town, office,
the quadrotor experiment of Sec. 4.2); :class:`ConnectivityParams` is the
validated parameter set every function of the connectivity force takes.
"""

from __future__ import annotations

from dataclasses import dataclass

# Table 2 of the paper: (R's, Rs), (Ro, R'o), (Rc, R'c), (lambda2_min, lambda2_null).
TABLE2: dict[str, dict[str, float]] = {
    "outdoor": {  # "empty space and town"
        "rs_inner_m": 2.5, "rs_m": 6.0, "ro_m": 0.75, "ro_outer_m": 1.75,
        "rc_m": 1.0, "rc_outer_m": 2.5, "lambda2_min": 0.0, "lambda2_null": 1.0,
    },
    "office": {
        "rs_inner_m": 1.1, "rs_m": 2.5, "ro_m": 0.25, "ro_outer_m": 0.6,
        "rc_m": 0.8, "rc_outer_m": 1.1, "lambda2_min": 0.0, "lambda2_null": 1.0,
    },
    "experiment": {  # Sec. 4.2, the quadrotor experiment
        "rs_inner_m": 1.4, "rs_m": 2.5, "ro_m": 0.5, "ro_outer_m": 0.75,
        "rc_m": 1.0, "rc_outer_m": 1.4, "lambda2_min": 0.0, "lambda2_null": 1.0,
    },
}  # fmt: skip
_OUTDOOR = TABLE2["outdoor"]

# Table 2's traveling parameters (Table 3 for the experiment): Rgrid, sigma, v_cruise,
# (x_c, x_M) as fractions of v_cruise, Rz; Delta t = 3 s is the targets' stay_s.
TRAVEL_TABLE2: dict[str, dict[str, float]] = {
    "outdoor": {"r_grid_m": 0.75, "sigma": 3.0, "v_cruise_mps": 3.0,
                "xc_frac": 0.1, "xm_frac": 0.6, "rz_m": 1.8},
    "office": {"r_grid_m": 0.25, "sigma": 3.0, "v_cruise_mps": 1.0,
               "xc_frac": 0.1, "xm_frac": 0.6, "rz_m": 1.0},
    "experiment": {"r_grid_m": 0.2, "sigma": 3.0, "v_cruise_mps": 0.5,
                   "xc_frac": 0.2, "xm_frac": 0.7, "rz_m": 0.75},
}  # fmt: skip


@dataclass(frozen=True)
class ConnectivityParams:
    """The parameters of Table 2 (defaults: empty space and town column).

    Attributes
    ----------
    rs_inner_m, rs_m
        ``(R's, Rs)``: the range factor falls from 1 to 0 between them.
    ro_m, ro_outer_m
        ``(Ro, R'o)``: the obstacle factor rises from 0 to 1 between them.
    rc_m, rc_outer_m
        ``(Rc, R'c)``: the collision factor rises from 0 to 1 between them.
    lambda2_min, lambda2_null
        Where the potential is infinite / becomes zero.
    potential_gain
        ``k_V`` (newtons); the paper does not state it.
    """

    rs_inner_m: float = _OUTDOOR["rs_inner_m"]
    rs_m: float = _OUTDOOR["rs_m"]
    ro_m: float = _OUTDOOR["ro_m"]
    ro_outer_m: float = _OUTDOOR["ro_outer_m"]
    rc_m: float = _OUTDOOR["rc_m"]
    rc_outer_m: float = _OUTDOOR["rc_outer_m"]
    lambda2_min: float = _OUTDOOR["lambda2_min"]
    lambda2_null: float = _OUTDOOR["lambda2_null"]
    potential_gain: float = 1.0

    def __post_init__(self) -> None:
        if not 0 < self.rs_inner_m < self.rs_m:
            raise ValueError("need 0 < R's < Rs")
        if not 0 < self.ro_m < self.ro_outer_m:
            raise ValueError("need 0 < Ro < R'o")
        if not 0 < self.rc_m < self.rc_outer_m:
            raise ValueError("need 0 < Rc < R'c")
        if not self.rc_outer_m < self.rs_m:
            raise ValueError("need R'c < Rs so that collision neighbours are sensing neighbours")
        if not 0 <= self.lambda2_min < self.lambda2_null:
            raise ValueError("need 0 <= lambda2_min < lambda2_null")
        if not self.potential_gain > 0:
            raise ValueError("potential_gain must be > 0")

    @property
    def transition_width_m(self) -> float:
        """The narrowest of the three transition bands (sets the integrator's step)."""
        return min(
            self.rs_m - self.rs_inner_m, self.ro_outer_m - self.ro_m, self.rc_outer_m - self.rc_m
        )
