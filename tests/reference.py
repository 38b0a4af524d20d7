"""Independent reference solutions used by several tests (written separately from the
package's models on purpose)."""
import numpy as np

G = 9.81


def sliding_block(acc_base, t, mu, dt=1e-5, v0=0.0, velocity=False):
    """Relative displacement of a rigid block on a base with Coulomb friction mu, base
    acceleration acc_base(t) (m/s^2): u'' = -a_b - mu g sign(u') while sliding; it sticks
    when u' crosses zero with |a_b| <= mu g. Initial relative velocity v0 (m/s). Explicit,
    step dt (s), returns u at t (and u' at t with ``velocity``)."""
    n = int(round(t[-1] / dt))
    u, v = 0.0, float(v0)
    vs = np.empty(n + 1)
    vs[0] = v
    out = np.empty(n + 1)
    out[0] = 0.0
    for k in range(n):
        a_b = acc_base(k * dt)
        if v == 0.0 and abs(a_b) <= mu * G:
            acc = 0.0
        else:
            s = np.sign(v) if v != 0.0 else -np.sign(a_b)
            acc = -a_b - mu * G * s
        v_new = v + acc * dt
        if v != 0.0 and np.sign(v_new) != np.sign(v) and abs(acc_base((k + 1) * dt)) <= mu * G:
            v_new = 0.0
        u += 0.5 * (v + v_new) * dt
        v = v_new
        out[k + 1] = u
        vs[k + 1] = v
    tt = np.arange(n + 1) * dt
    if velocity:
        return np.interp(t, tt, out), np.interp(t, tt, vs)
    return np.interp(t, tt, out)
