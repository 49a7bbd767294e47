"""Theories of the interfacial stiffness the paper compares with (pure numpy/scipy).

- Persson's theory of the mean separation ``u_bar(p)`` and ``K = -dp/du_bar`` for any
  isotropic PSD ``C(q)`` (Persson, PRL 99, 125502 (2007); Yang &
  Persson, PRL 100, 024303 (2008)), and of the contact area ``A(p)/A0`` (Persson,
  J. Chem. Phys. 115, 3840 (2001)).
- The paper's finite-size scaling theory (Appendix B): ``theta0``, ``theta1``, ``theta(H)``,
  the power-law stiffness (paper Eq. 12) and the crossover pressure (paper Eq. 13).
- The Hertz regime of a single asperity, and the block-compression correction of the
  paper's experiment (paper Eq. C3).

Units: any consistent set; ``q`` in 1/length, ``C`` in length^4, pressures in the unit of
``modulus``, stiffness per area in pressure/length.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy import integrate, special

from ..conventions.warnings import user_level
from ..reference import hertz

Values = np.ndarray | float  # one value, or an array of them (the result has its shape)
GAMMA = 0.4  # Persson's gamma (and the paper's u0 = gamma h_rms)
NAYAK_BETA = np.sqrt(8 / (3 * np.pi))  # mean summit curvature factor for q1/q0 >> 1
KAPPA0 = 2 / 5  # Hertz mesoasperity energy prefactor (Appendix B)


# -- finite-size scaling theory (paper Appendix B) -------------------------------------------


def kappa1(hurst: Values, gamma: float = GAMMA) -> np.ndarray:
    """``kappa1 = gamma ((2 - H) / (pi^4 beta^2 H))^(1/2)`` (Appendix B)."""
    h = np.asarray(hurst, dtype=float)
    return gamma * np.sqrt((2 - h) / (np.pi**4 * NAYAK_BETA**2 * h))


def inverse_theta_parts(hurst: Values, gamma: float = GAMMA) -> tuple[np.ndarray, np.ndarray]:
    """``(1/theta0, 1/theta1)``: the Hertz-mesoasperity and microroughness contributions.

    ``1/theta_{0/1} = (1+2H)/(1+H) (3/(4 pi))^(H/(1+H)) (pi^4 beta^2 H/(2-H))^(1/(2+2H))
    kappa_{0/1}`` (paper, Appendix B; Fig. 2).
    """
    h = np.asarray(hurst, dtype=float)
    common = (
        (1 + 2 * h)
        / (1 + h)
        * (3 / (4 * np.pi)) ** (h / (1 + h))
        * (np.pi**4 * NAYAK_BETA**2 * h / (2 - h)) ** (1 / (2 + 2 * h))
    )
    return common * KAPPA0, common * kappa1(h, gamma)


def theta(hurst: Values, gamma: float = GAMMA) -> np.ndarray:
    """The prefactor of paper Eq. 12, ``1/theta = 1/theta0 + 1/theta1`` (paper Fig. 2)."""
    inv0, inv1 = inverse_theta_parts(hurst, gamma)
    return 1.0 / (inv0 + inv1)


def roll_off_factor(hurst: float, rolloff_ratio: float) -> float:
    """``s`` with ``1/s = 1 + H (1 - (lambda_r/L)^2)`` (paper Eq. 12).

    ``rolloff_ratio`` is ``L/lambda_r``.
    """
    return 1.0 / (1.0 + hurst * (1.0 - rolloff_ratio**-2.0))


def _size_factor(h_rms: float, length: float, rolloff_ratio: float) -> float:
    """``h_rms/(2 pi lambda_r) * lambda_r^2/L^2``, the combination in paper Eqs. 12-13."""
    lam_r = length / rolloff_ratio
    return h_rms / (2 * np.pi * lam_r) * (lam_r / length) ** 2


def finite_size_stiffness(
    pressure: Values,
    modulus: float,
    h_rms: float,
    hurst: float,
    length: float,
    rolloff_ratio: float,
    gamma: float = GAMMA,
) -> np.ndarray:
    """Power-law regime ``K(p)`` of paper Eq. 12 (per area)::

    K h_rms / E* = theta (h_rms/(2 pi lambda_r) lambda_r^2/L^2)^(H/(1+H))
                         (p/(s^(1/2) E*))^(1/(1+H))
    """
    p = np.asarray(pressure, dtype=float)
    s = roll_off_factor(hurst, rolloff_ratio)
    e = 1.0 / (1.0 + hurst)
    return (
        modulus
        / h_rms
        * theta(hurst, gamma)
        * _size_factor(h_rms, length, rolloff_ratio) ** (hurst * e)
        * (p / (np.sqrt(s) * modulus)) ** e
    )


@dataclass(frozen=True)
class Reading:
    """How paper Eq. 13 is evaluated: which ``q_r`` in ``q_r h_rms`` and in ``q_r L``, and
    whether with ``theta(H)`` or ``theta = 1``.

    Appendix B derives the crossover in dimensionless form, ``F_c/h_rms = s^(-1/2H)
    (theta gamma)^((1+H)/H)`` with the height ``q_r h_rms`` and the force ``F q_r^2/E* =
    p (q_r L)^2/E*``, so that ``p_c/E* = (q_r h_rms)/(q_r L)^2 s^(-1/2H)
    (theta gamma)^((1+H)/H)``.  ``height`` and ``size`` are the two ``q_r`` in units of
    ``pi/lambda_r``.
    """

    height: float  # q_r lambda_r/pi in q_r h_rms
    size: float  # q_r lambda_r/pi in q_r L
    unit_theta: bool  # theta = 1 instead of theta(H)


READINGS = {
    # paper Eq. 13 as printed: q_r = 2 pi/lambda_r (its definition under Eq. 5), theta(H)
    "printed": Reading(height=2.0, size=2.0, unit_theta=False),
    # how the paper computed its quoted p_c (Sec. IV, Appendix B "Discussion", Conclusions):
    # q_r h_rms with q_r = 2 pi/lambda_r, q_r L = pi L/lambda_r, theta = 1
    "paper": Reading(height=2.0, size=1.0, unit_theta=True),
    # deprecated: q_r = pi/lambda_r in both places, theta = 1 (half of "paper")
    "appendix": Reading(height=1.0, size=1.0, unit_theta=True),
}
CONVENTIONS = tuple(READINGS)


def _reading(convention: str | Reading) -> Reading:
    """The :class:`Reading` of ``convention`` (a name, or a reading used as given);
    ``"appendix"`` warns (deprecated)."""
    if isinstance(convention, Reading):
        return convention
    if convention not in READINGS:
        raise ValueError(f"convention must be one of {', '.join(CONVENTIONS)}, got '{convention}'")
    if convention == "appendix":
        warnings.warn(
            'convention="appendix" (q_r = pi/lambda_r in q_r h_rms too) gives half of what '
            "the paper's recipe gives for a surface's own h_rms: use \"paper\" (the recipe "
            'of its quoted p_c) or "printed"; "appendix" will be removed in 0.3.0',
            DeprecationWarning,
            stacklevel=user_level(),
        )
    return READINGS[convention]


def rolloff_wavevector(length: float, rolloff_ratio: float, convention: str = "printed") -> float:
    """The ``q_r`` of the size factor ``(q_r L)^2`` of paper Eq. 13 in ``convention``.

    ``"printed"``: ``2 pi/lambda_r`` (the paper's definition under Eq. 5).  ``"paper"``:
    ``pi/lambda_r``, Appendix B's ``q_r ~ pi/L`` (stated there for ``L = lambda_r``; taking
    it as ``pi L/lambda_r / L`` for ``L != lambda_r`` is this package's assumption, which
    the paper's quoted ``p_c`` at ``L/lambda_r = 8`` bears out).  ``"appendix"``
    (deprecated): the same ``pi/lambda_r``.
    """
    return _reading(convention).size * np.pi * rolloff_ratio / length


def crossover_pressure(
    modulus: float,
    h_rms: float,
    hurst: float,
    length: float,
    rolloff_ratio: float,
    gamma: float = GAMMA,
    convention: str | Reading = "printed",
) -> float:
    """``p_c`` of paper Eq. 13, where Eq. 12 meets ``K = p/(gamma h_rms)``::

        p_c / E* = h_rms/(2 pi lambda_r) lambda_r^2/L^2 s^(-1/2H) (theta gamma)^((1+H)/H)
                 = (q_r h_rms)/(q_r L)^2 s^(-1/2H) (theta gamma)^((1+H)/H)

    Parameters
    ----------
    modulus, h_rms, hurst, length, rolloff_ratio, gamma
        ``E*``, the surface's rms height, ``H``, ``L``, ``L/lambda_r`` and ``gamma``.
    convention
        Which ``q_r`` and ``theta`` (:data:`READINGS`):

        ``"printed"``
            The formula as printed: ``q_r = 2 pi/lambda_r`` in both places, ``theta(H)``.
            Only this reading makes Eq. 12 meet ``p/(gamma h_rms)`` at ``p_c``.
        ``"paper"``
            The recipe that gives the paper's three quoted values (``6e-5`` and ``3e-6`` for
            ``L/lambda_r`` = 1 and 8, Sec. IV and Appendix B; ``about 1 kPa`` for the
            syringe, Conclusions): ``q_r h_rms`` with ``q_r = 2 pi/lambda_r``, the size
            factor with Appendix B's ``q_r ~ pi/L`` (``q_r L = pi L/lambda_r``: for
            ``L != lambda_r`` this package's assumption), ``theta = 1``.  It is
            ``4 theta^(-(1+H)/H)`` times ``"printed"`` (5.0 at H = 0.7).  Its two ``q_r``
            are not the same, so Eq. 12 (in either ``q_r``) does not meet
            ``p/(gamma h_rms)`` at this ``p_c``: the recipe is the pure ``q_r ~ pi/L``
            reading with ``h_rms`` read as ``(2 pi/lambda_r) h_rms/(pi/lambda_r)``, twice
            the surface's.
        ``"appendix"``
            Deprecated (``DeprecationWarning``): ``q_r = pi/lambda_r`` in both places and
            ``theta = 1``, half of ``"paper"``.  It gives the paper's values only when fed
            ``h_rms = (q_r h_rms)/(pi/lambda_r)``, twice a surface's own ``h_rms``.

        A :class:`Reading` is used as given (no warning: ``READINGS["appendix"]`` is how the
        package itself still records the deprecated value).
    """
    reading = _reading(convention)
    s = roll_off_factor(hurst, rolloff_ratio)
    q_height = reading.height * np.pi * rolloff_ratio / length
    q_size = reading.size * np.pi * rolloff_ratio / length
    th = 1.0 if reading.unit_theta else theta(hurst, gamma)
    return float(
        modulus
        * q_height
        * h_rms
        / (q_size * length) ** 2
        * s ** (-1.0 / (2 * hurst))
        * (th * gamma) ** ((1 + hurst) / hurst)
    )


def linear_stiffness(pressure: Values, h_rms: float, gamma: float = GAMMA) -> np.ndarray:
    """The exponential regime: ``K = p / u0`` with ``u0 = gamma h_rms`` (paper Eq. 1)."""
    return np.asarray(pressure, dtype=float) / (gamma * h_rms)


def hertz_stiffness(
    pressure: Values, modulus: float, radius: float, area: float, cell: float | None = None
) -> np.ndarray:
    """Single-asperity (Hertz) regime, ``K ~ p^(1/3)``, per apparent area ``A0``.

    ``F = p A0`` on one sphere (:mod:`~petsc_contact.reference.hertz`): ``K = 2 E* a / A0``
    on a half-space; with ``cell`` the side ``L`` of a square periodic cell (``A0 = L^2``),
    ``1/(K A0) = 1/(2 E* a) - c/(E* L)`` (:func:`~petsc_contact.reference.hertz.
    periodic_stiffness`, ``c = 1.2415``): the periodic simulation's Hertz limit.
    """
    a = hertz.radius_at_force(np.asarray(pressure, dtype=float) * area, radius, modulus)
    if cell is None:
        return np.asarray(2 * modulus * a / area)
    return np.asarray(hertz.periodic_stiffness(a, modulus, cell) / area)


# -- Persson theory ---------------------------------------------------------------------------


def _separation_kernel(t: np.ndarray, gamma: float) -> np.ndarray:
    """``[gamma + 3 (1 - gamma) erf(t)^2] exp(-t^2)``."""
    return (gamma + 3 * (1 - gamma) * special.erf(t) ** 2) * np.exp(-t * t)


def _tail_integral(
    gamma: float, t_min: float = 1e-12, t_max: float = 12.0, points: int = 4001
) -> tuple[np.ndarray, np.ndarray]:
    """``I(t0) = int_t0^inf dt/t kernel(t)`` on a log grid of ``t0`` (cumulative quadrature
    in ``ln t``; the integrand is smooth there and below 1e-60 beyond ``t_max``)."""
    lnt = np.linspace(np.log(t_min), np.log(t_max), points)
    f = _separation_kernel(np.exp(lnt), gamma)
    tail = integrate.cumulative_trapezoid(f[::-1], -lnt[::-1], initial=0.0)[::-1]
    return lnt, tail


ROOT_POINTS = 4000  # points of the sqrt(q - q0) grid Persson's integrals are evaluated on


def persson_w(q: np.ndarray, psd: np.ndarray) -> np.ndarray:
    """``w(q) = (pi int_q0^q dq' q'^3 C(q'))^(-1/2)`` (``inf`` at the first ``q``)."""
    cum = integrate.cumulative_trapezoid(q**3 * psd, q, initial=0.0)
    with np.errstate(divide="ignore"):
        return 1.0 / np.sqrt(np.pi * cum)


@dataclass(frozen=True)
class _RootGrid:
    """Persson's integrals on ``q = q0 + s^2``.

    ``w(q)`` diverges like ``(q - q0)^(-1/2)`` at ``q0``: integrable, but a trapezoid rule on
    ``q`` drops its weight.  In ``s`` the measure ``dq = 2 s ds`` cancels the divergence, so
    ``ws = w 2s`` is finite everywhere (``2 / sqrt(pi q0^3 C(q0))`` at ``s = 0``) and every
    integrand is smooth.  ``C`` is interpolated log-log from the caller's grid.
    """

    s: np.ndarray
    q: np.ndarray
    psd: np.ndarray
    w: np.ndarray  # inf at s = 0
    ws: np.ndarray  # w 2s: the weight of the integrals in s

    @classmethod
    def of(cls, q: np.ndarray, psd: np.ndarray, points: int = ROOT_POINTS) -> _RootGrid:
        q = np.asarray(q, dtype=float)
        psd = np.asarray(psd, dtype=float)
        if q.ndim != 1 or q.shape != psd.shape or q.size < 2 or np.any(np.diff(q) <= 0):
            raise ValueError("q must increase and match psd in shape (at least 2 points)")
        if not psd[0] > 0:
            raise ValueError("the spectrum must be positive at its first wavevector q0")
        end = np.sqrt(q[-1] - q[0])
        # uniform in s, and geometric towards s = 0, where the inner integrals switch on at
        # s ~ w^-1 ~ p/E* (any load down to 1e-9 E* is resolved)
        n = max(points, q.size)
        s = np.unique(np.r_[np.linspace(0.0, end, n), np.geomspace(end * 1e-10, end, n)])
        qs = q[0] + s * s
        positive = psd > 0
        log_c = np.interp(np.log(qs), np.log(q[positive]), np.log(psd[positive]))
        cs = np.where(qs <= q[positive][-1], np.exp(log_c), 0.0)
        cum = integrate.cumulative_trapezoid(qs**3 * cs * 2 * s, s, initial=0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            w = 1.0 / np.sqrt(np.pi * cum)
            ws = np.where(s > 0, w * 2 * s, 2.0 / np.sqrt(np.pi * q[0] ** 3 * psd[0]))
        return cls(s, qs, cs, w, ws)

    def integrate(self, integrand: np.ndarray) -> np.ndarray:
        """``int dq f(q) w(q)`` given ``integrand = f w 2s`` on the grid (last axis)."""
        return np.asarray(integrate.trapezoid(integrand, self.s, axis=-1))


def _tail_constant(gamma: float) -> float:
    """``c = lim_{t -> 0} [I(t) - gamma ln(1/t)]``, with ``I`` the tabulated tail integral."""
    lnt, tail = _tail_integral(gamma)
    return float(tail[0] + gamma * lnt[0])


def persson_mean_gap(
    pressure: Values, q: np.ndarray, psd: np.ndarray, modulus: float, gamma: float = GAMMA
) -> np.ndarray:
    """Persson's mean separation ``u_bar(p)``::

        u_bar = sqrt(pi) int dq q^2 C(q) w(q) int_p^inf dp'/p' kernel(w(q) p'/E*)

    The inner integral is the universal ``I(w p/E*)``, tabulated once.  The outer one is
    exact at ``q0``, where ``w`` diverges (:class:`_RootGrid`).

    Parameters
    ----------
    pressure
        Nominal pressures (scalar or array).
    q, psd
        Increasing wavevector magnitudes from ``q0`` to ``q1`` and the isotropic PSD
        ``C(q)`` on them (normalised as ``h_rms^2 = 2 pi int q C dq``): the prescribed
        (continuum) spectrum on a fine grid, or a realisation's radial average.
    """
    p = np.atleast_1d(np.asarray(pressure, dtype=float))
    grid = _RootGrid.of(q, psd)
    lnt, tail = _tail_integral(gamma)
    t0 = np.outer(p / modulus, grid.w)
    with np.errstate(invalid="ignore"):
        inner = np.interp(np.log(np.maximum(t0, 1e-300)), lnt, tail, left=np.nan, right=0.0)
    # below the table, I(t0) = I(t_min) + (gamma + ...) ln(t_min/t0) ~ gamma ln(t_min/t0)
    low = t0 < np.exp(lnt[0])
    inner[low] = tail[0] + gamma * (lnt[0] - np.log(np.maximum(t0[low], 1e-300)))
    u = np.sqrt(np.pi) * grid.integrate(grid.q**2 * grid.psd * grid.ws * inner)
    return u if np.ndim(pressure) else u[0]


def persson_stiffness(
    pressure: Values, q: np.ndarray, psd: np.ndarray, modulus: float, gamma: float = GAMMA
) -> np.ndarray:
    """``K = -dp/du_bar`` of Persson's theory, analytically differentiated::

    -du_bar/dp = sqrt(pi)/p int dq q^2 C(q) w(q) kernel(w(q) p/E*)
    """
    p = np.atleast_1d(np.asarray(pressure, dtype=float))
    grid = _RootGrid.of(q, psd)
    t0 = np.outer(p / modulus, grid.w)
    integrand = grid.q**2 * grid.psd * grid.ws * _separation_kernel(t0, gamma)
    k = p / (np.sqrt(np.pi) * grid.integrate(integrand))
    return k if np.ndim(pressure) else k[0]


def area_fraction(pressure: Values, pressure_rms: float) -> np.ndarray:
    """Persson's contact area ``A/A0 = erf(p / (sqrt(2) sigma))`` at the nominal pressure
    ``p``, with ``sigma`` the rms pressure of full contact.

    The pressure distribution of Persson's theory spreads by diffusion as finer roughness is
    resolved, from ``delta(p' - p)`` to a Gaussian of variance ``sigma^2`` at full
    resolution, with ``p' = 0`` absorbing (a point that loses contact never regains it); the
    mass left at ``p' > 0`` is the contact area.  For ``p << sigma`` it is linear,
    ``A/A0 = sqrt(2/pi) p/sigma``.
    """
    return special.erf(np.asarray(pressure, dtype=float) / (np.sqrt(2) * pressure_rms))


def spectrum_rms_slope(q: np.ndarray, psd: np.ndarray) -> float:
    """The rms slope of an isotropic spectrum, ``h'_rms = (2 pi int dq q^3 C(q))^(1/2)``
    (``C`` normalised as ``h_rms^2 = 2 pi int dq q C``; trapezoids on ``q``)."""
    return float(np.sqrt(2 * np.pi * integrate.trapezoid(q**3 * psd, q)))


def persson_area(pressure: Values, q: np.ndarray, psd: np.ndarray, modulus: float) -> np.ndarray:
    """Persson's contact area ``A/A0`` at the nominal ``pressure`` for the isotropic PSD
    ``C(q)`` on ``q`` (normalised as ``h_rms^2 = 2 pi int dq q C``)::

        A/A0 = erf(sqrt(2) p / (E* h'_rms))  ~  sqrt(8/pi) p / (E* h'_rms)  for small p

    Full contact presses each mode ``h(q)`` with ``E* |q| h(q)/2``, so its rms pressure is
    ``sigma = E* h'_rms/2`` (:func:`spectrum_rms_slope`), the width :func:`area_fraction`
    takes (Persson, J. Chem. Phys. 115, 3840 (2001): ``P(q1) = erf(w(q1) p/E*)`` in
    :func:`persson_w`'s ``w``).  The small-load
    prefactor ``sqrt(8/pi) = 1.60`` lies 20-25% below the ``kappa ~ 2`` that simulations of
    self-affine surfaces find (Hyun, Pei, Molinari & Robbins, PRE 70, 026117 (2004);
    Prodanov, Dapp & Mueser, Tribol. Lett. 53, 433 (2014)): the theory's area is a lower
    estimate.
    """
    return area_fraction(pressure, modulus * spectrum_rms_slope(q, psd) / 2)


def persson_exponential(
    q: np.ndarray, psd: np.ndarray, gamma: float = GAMMA
) -> tuple[float, float]:
    """``(beta, u0)`` of Persson's small-load law ``p = beta E* exp(-u_bar/u0)`` (paper
    Eq. 3 with ``p0 = beta E*``), in closed form.

    For ``p -> 0`` the inner integral is ``I(t) = gamma ln(1/t) + c`` with ``t = w p/E*``,
    so ``u_bar = u0 ln(E*/p) + sqrt(pi) int dq q^2 C w (c - gamma ln w)`` with
    ``u0 = gamma sqrt(pi) int dq q^2 C w``, and ``beta`` is the exponential of the second
    term over ``u0``.  Both integrals are evaluated exactly at ``q0``.
    """
    grid = _RootGrid.of(q, psd)
    weight = grid.q**2 * grid.psd * grid.ws
    u0 = gamma * np.sqrt(np.pi) * float(grid.integrate(weight))
    # c - gamma ln w = c - gamma ln(w s) + gamma ln s: the first part is smooth (w s -> the
    # finite ws(0)/2 at s = 0), the second has an integrable log, integrated in closed form
    ws_half = grid.ws / 2
    smooth = float(grid.integrate(weight * (_tail_constant(gamma) - gamma * np.log(ws_half))))
    s_grid = grid.s
    with np.errstate(divide="ignore", invalid="ignore"):
        log_part = np.where(s_grid > 0, (weight - weight[0]) * np.log(s_grid), 0.0)
    end = s_grid[-1]
    logarithmic = float(grid.integrate(log_part)) + weight[0] * end * (np.log(end) - 1.0)
    constant = np.sqrt(np.pi) * (smooth + gamma * logarithmic)
    return float(np.exp(constant / u0)), u0


# -- the paper's experiment (Appendix C) -----------------------------------------------------


def block_corrected_stiffness(
    pressure: np.ndarray, displacement: np.ndarray, block_modulus: float, thickness: float
) -> tuple[np.ndarray, np.ndarray]:
    """Interfacial stiffness from a measured ``p(s)`` table (paper Eq. C3).

    ``K* = dp/ds`` by second-order finite differences on the (possibly non-uniform) table,
    then ``K = K* / (1 - K* d/E')``.

    Returns
    -------
    k_star, k
        Both at the table's pressures; ``K`` is ``nan`` where ``K* d/E' >= 1`` (the block's
        own compression dominates, the paper's "great sensitivity" region) and where
        ``K* <= 0`` (the pressure does not rise with the displacement: no stiffness).
    """
    p = np.asarray(pressure, dtype=float)
    s = np.asarray(displacement, dtype=float)
    if p.ndim != 1 or p.shape != s.shape or p.size < 3:
        raise ValueError("need at least 3 (pressure, displacement) rows")
    order = np.argsort(s)
    p, s = p[order], s[order]
    if np.any(np.diff(s) <= 0):
        raise ValueError("displacements must be distinct")
    k_star = np.gradient(p, s, edge_order=2)
    denom = 1.0 - k_star * thickness / block_modulus
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where((denom > 0) & (k_star > 0), k_star / denom, np.nan)
    inverse = np.empty_like(order)
    inverse[order] = np.arange(order.size)
    return k_star[inverse], k[inverse]
