"""The contact core: the ``ContactProblem`` protocol and the one step driver (:mod:`step`),
with its two implementations, the periodic QP in the gap (:mod:`periodic`) and the padded
free-boundary QP in the pressure of a rigid punch (:mod:`punch`)."""
