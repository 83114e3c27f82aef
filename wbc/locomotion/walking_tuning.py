"""The walking motion's tuning: thresholds, rates and weights, each with why it is what it is."""

#: A descending foot has landed when it is within TOUCH_M [m] of the ground it left from,
#: or within NEAR_M and stopped (slower than STOPPED_MPS [m/s]: the ground holds it). A foot
#: counted as landed while still moving down would make the estimator, which takes a stance
#: foot as fixed, carry the base down with it (5 mm/s of height drift in a trot at 6 mm).
TOUCH_M, NEAR_M, STOPPED_MPS = 0.002, 0.012, 0.05
#: How fast a late foot keeps going down [m/s], and for how long at most [s].
LATE_SPEED_MPS, LATE_MAX_S = 0.3, 0.15
#: Accelerations [m/s^2, rad/s^2] at which the commanded velocity follows a new command.
LINEAR_ACCEL, YAW_ACCEL = 2.0, 4.0
#: Deceleration [m/s^2] of the commanded velocity after a stop: 1 m/s to rest in 0.33 s.
STOP_ACCEL = 3.0
#: Farthest the CoM reference runs ahead of the CoM [m]: it is dragged, never wound up.
COM_LEAD_M = 0.06
#: Weight of the CoM task while walking: ten times the standing default, so that the QP
#: does not lift the body to help a swinging foot up (it did by 2-3 cm a step at 20).
COM_WEIGHT = 200.0
#: Swing joints' driver damping [N m s/rad] and the bound of the desired joint velocity's
#: lead [rad/s] while walking (standing: 2 and 1): a 0.2 s swing moves the joints at up
#: to 10 rad/s, where joint damping the model lacks (2 N m s/rad on the default plant) lags
#: the foot 4 cm and the foot tasks lift the body to make up for it; with these the lag is
#: 1.5 cm and the base holds its height.
SWING_KD, VELOCITY_LEAD_RAD_S = 4.0, 4.0
#: Rate [1/s] at which the CoM height target integrates the base height's error: the CoM
#: task holds the whole body's CoM, and the legs' swings and the stance legs' compliance
#: leave the base about 1 cm off its height without it.
HEIGHT_KI, HEIGHT_TRIM_M = 2.0, 0.03
#: Time [s] the CoM takes, once the feet are down after a stop, back over them.
SETTLE_S = 0.3
#: Stop stepping once slower than this [m/s] and turning slower than this [rad/s], or after
#: STOP_STEPPING_S [s], then settle. A trot at 1 m/s sways sideways at up to 0.3 m/s (its
#: capture point then 5 cm off, well inside four feet) and rocks its heading at 0.5 rad/s.
STOP_SPEED_MPS, STOP_YAW_RATE, STOP_STEPPING_S = 0.3, 0.8, 0.6
