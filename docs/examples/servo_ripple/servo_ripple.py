"""A periodic transmission error of the servos (the walk-through of docs/effects.md)."""
import numpy as np

from phantom_cad.calibration.effects import Effect, Param, Signature, register_effect
from phantom_cad.kinematics.topology import CHAINS

W = 2 * np.pi / np.radians(40.0)        # the period diagnose reported: 40 deg of servo angle
SERVOS = [c.servo for c in CHAINS]


@register_effect
class ServoRipple(Effect):
    name = "servo_ripple"
    stage = "servo"                      # acts on the servo's output angle, before the cosine law
    explanation = "the chain wobbles with period 40 deg of servo angle: a periodic gear error"
    formula = "u_eff = u + a sin(w u) + b (cos(w u) - 1), w = 2 pi / 40 deg, zero at rest"
    leaves = Signature(direction="same", at_rest="zero", trend="flat", joints="all", periodic=True, reversal="none")

    def parameters(self, hand):
        return [Param(f"u{c.servo + 1}_{k}_deg", -5.0, 5.0, (0.5, 2.0), True, c.q_index, True,
                      f"{k} amplitude of servo u{c.servo + 1}'s ripple") for c in CHAINS for k in "ab"]

    def ripple(self, u, x):
        a, b, wu = np.radians(x[0::2]), np.radians(x[1::2]), W * u[..., SERVOS]
        return a * np.sin(wu) + b * (np.cos(wu) - 1.0)

    def apply(self, ctx, x):
        ctx.u_eff[:, SERVOS] += self.ripple(ctx.u, x)

    def invert(self, hand, u_eff, x):    # the control law: u + ripple(u) = u_eff, by fixed point
        u = np.array(u_eff, dtype=float)
        for _ in range(60):              # converges: |d ripple / du| = w |a, b| < 1
            u[..., SERVOS] = u_eff[..., SERVOS] - self.ripple(u, x)
        return u
