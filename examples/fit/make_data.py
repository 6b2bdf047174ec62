"""Synthetic AFM ramp-hold curve for the `nlvid fit` example, computed
independently of nlvid: Lee-Radok Hertz force (incompressible)
F(t) = 16/3 sqrt(R) * int_0^t G(t - s) d(delta^1.5)/ds ds, delta = v*s up to
the ramp end, with G(t) = G0 (ginf + g1 e^-t/tau1 + g2 e^-t/tau2), by
midpoint quadrature in s = w^2; 2 % Gaussian noise (seeded). Writes
cell1.csv with piezo Z = delta + d and deflection d in volts."""
import math
import random

R, V, T_RAMP, T_END = 5e-6, 1e-6, 1.0, 10.0  # as `nlvid build --model hertz-prony`
K, SENS = 1.0, 50e-9  # spring constant N/m, deflection sensitivity m/V
G0, G1, TAU1, G2, TAU2 = 1200.0, 0.35, 0.3, 0.3, 6.0


def relax(t):
    return G0 * (1 - G1 - G2 + G1 * math.exp(-t / TAU1) + G2 * math.exp(-t / TAU2))


def force(t):
    top = math.sqrt(min(t, T_RAMP))
    n = 4000
    h = top / n
    s = 0.0
    for i in range(n):
        w = (i + 0.5) * h
        # d(delta^1.5)/ds ds = 1.5 v^1.5 s^0.5 ds, ds = 2 w dw
        s += relax(t - w * w) * 1.5 * V ** 1.5 * w * 2 * w * h
    return 16.0 / 3.0 * math.sqrt(R) * s


rng = random.Random(6)
times = [i * 0.01 for i in range(int(T_END / 0.01) + 1)]
clean = [force(t) for t in times]
peak = max(clean)
with open("cell1.csv", "w") as f:
    f.write("time [s],piezo [um],deflection [V]\n")
    for t, fc in zip(times, clean):
        F = fc + 0.02 * peak * rng.gauss(0.0, 1.0)
        d = F / K
        delta = V * min(t, T_RAMP)
        f.write(f"{t:.4f},{(delta + d) * 1e6:.9f},{d / SENS:.9f}\n")
print("wrote cell1.csv; truth G0 =", G0, "g1 =", G1, "tau1 =", TAU1, "g2 =", G2, "tau2 =", TAU2)
