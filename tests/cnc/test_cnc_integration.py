"""Digital-integration interpolators (textbook 4.2.1.2) in the soft PLC: linear with
acceleration / deceleration (eq. 10-11), circular by rotating the radius vector (eq. 12-14)
within the accumulated-error bound of eq. (17)-(19)/(22)."""
from __future__ import annotations

import math

from hypothesis import given, settings, strategies as st

from cnc_st import integ_circular, integ_linear

lengths = st.integers(-1500, 1500).map(float)


@settings(max_examples=30, deadline=None)
@given(dx=lengths, dy=lengths, dz=lengths, vmax=st.floats(2.0, 20.0), a=st.floats(0.05, 1.0))
def test_linear_axes_proportional_end_reached_speed_within_limits(dx, dy, dz, vmax, a):
    run = integ_linear().run(DX=dx, DY=dy, DZ=dz, VMax=vmax, A=a)
    n = run["N"]
    pts = run.points("PX", "PY", "PZ")
    speeds = run["PV"][: n + 1]
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    if length == 0:
        assert n == 0
        return
    assert pts[-1] == (dx, dy, dz), f"ended at {pts[-1]}"
    for p in pts:          # the axis increments stay proportional: every point on the line
        along = (p[0] * dx + p[1] * dy + p[2] * dz) / length
        off = math.sqrt(max(0.0, sum(c * c for c in p) - along * along))
        assert off < 1e-6 * length, f"{p} is {off} off the line"
    for (p, q) in zip(pts, pts[1:]):
        travel = math.dist(p, q)
        assert travel <= vmax + 1e-9, f"{travel} per quantum > VMax {vmax}"
    for v0, v1 in zip(speeds, speeds[1:]):
        assert 0 < v1 <= vmax + 1e-12
        assert abs(v1 - v0) <= a + 1e-12, f"speed jumped {v0} -> {v1} (A = {a})"
    # the profile: cruising at VMax on a long segment, a ramp (not a jump) at both ends
    if length > vmax * vmax / a + 4 * vmax:
        assert max(speeds) == vmax
    assert speeds[1] <= a + 1e-12 and speeds[-1] <= vmax


@settings(max_examples=30, deadline=None)
@given(radius=st.floats(20.0, 200.0), a0=st.floats(0, 2 * math.pi), sweep=st.floats(0.1, 2 * math.pi),
       ccw=st.booleans(), vmax=st.floats(2.0, 20.0), accel=st.floats(0.05, 2.0))
def test_circular_error_within_the_accumulated_bound(radius, a0, sweep, ccw, vmax, accel):
    i, j = radius * math.cos(a0), radius * math.sin(a0)
    a1 = a0 + (sweep if ccw else -sweep)
    xe, ye = radius * math.cos(a1), radius * math.sin(a1)
    run = integ_circular().run(I=i, J=j, XE=xe, YE=ye, Ccw=ccw, VMax=vmax, A=accel)
    assert not run["Error"]
    n = run["N"]
    pts = run.points("PX", "PY")
    phis, bounds = run["PPhi"][: n + 1], run["PBound"][: n + 1]
    assert pts[-1] == (xe, ye)
    sign = 1 if ccw else -1
    dphi = vmax / radius                     # the largest step
    for k in range(1, n):                    # the last point is the programmed end point
        exact = (radius * math.cos(a0 + sign * phis[k]), radius * math.sin(a0 + sign * phis[k]))
        err = math.dist(pts[k], exact)
        # eq. (17)-(19): the sum of R dphi^3 / 3!, with what the textbook's first-member
        # estimate leaves out: the next term of the series (a factor 1 + dphi^2 / 32) and the
        # approximate rotation's norm sqrt(1 + dphi^4 / 4) carrying earlier errors along;
        # plus the rounding of LREAL
        allowed = bounds[k] * (1 + dphi * dphi / 32) * (1 + dphi ** 4 / 8) ** k + 1e-12 * radius * k
        assert err <= allowed, f"step {k}: error {err:.3e} > bound {allowed:.3e}"
    # eq. (22): with the largest step dphi = VMax / R, N R dphi^3 / 6
    assert bounds[n - 1] <= n * radius * dphi ** 3 / 6 + 1e-15
    # a quantum's chord: R dphi, times sqrt(1 + dphi^2 / 4) for the approximate rotation
    for p, q in zip(pts, pts[1:-1]):
        assert math.dist(p, q) <= math.hypot(*p) * dphi * math.sqrt(1 + dphi * dphi / 4) + 1e-9


def test_circular_full_circle_comes_back_to_the_start():
    run = integ_circular().run(I=100.0, J=0.0, XE=100.0, YE=0.0, Ccw=False, VMax=2.0, A=0.1)
    n = run["N"]
    assert run["PPhi"][n] == 2 * math.pi
    assert min(y for _, y in run.points("PX", "PY")) < -99.9       # went round through -Y first (CW)
    assert run["PY"][1] < 0
