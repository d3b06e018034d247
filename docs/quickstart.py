import numpy as np

import burstloc

rng = np.random.default_rng(0)
head = 50.0 + rng.normal(0.0, 0.01, 5_000)  # pressure head at one meter [m], 1 cm noise
head[3_000:] -= 2.0  # a burst at sample 3000: the head drops by 2 m

detector = burstloc.Cusum(threshold=0.5, drift=0.05)
for alarm in detector.update_many(head):  # or detector.update(x), one sample at a time
    print(alarm)
