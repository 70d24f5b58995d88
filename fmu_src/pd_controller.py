"""A PD controller as an FMI 2.0 co-simulation slave: the second FMU of the coupled scenario.

Inputs y (m) and v (m/s), a measured position and velocity along one axis; output
F = −kp (y − reference) − kd v (N), with direct feedthrough (the output follows the inputs at
once, so a master can read F right after setting y and v). The controller has no state.
"""
from pythonfmu import Fmi2Slave, Real
from pythonfmu.enums import Fmi2Causality, Fmi2Initial, Fmi2Variability


class inerter_pd_controller(Fmi2Slave):
    author = "inerter"
    description = "PD controller F = -kp (y - reference) - kd v, direct feedthrough"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.kp = 200.0
        self.kd = 5.0
        self.reference = 0.0
        self.y = 0.0
        self.v = 0.0
        fixed = dict(causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed)
        self.register_variable(Real("kp", description="proportional gain", **fixed))
        self.register_variable(Real("kd", description="derivative gain", **fixed))
        self.register_variable(Real("reference", description="set point of y", **fixed))
        self.register_variable(Real("y", causality=Fmi2Causality.input, description="measured position"))
        self.register_variable(Real("v", causality=Fmi2Causality.input, description="measured velocity"))
        self.register_variable(Real("F", causality=Fmi2Causality.output, initial=Fmi2Initial.exact,
                                    description="actuator force", getter=self.force))

    def force(self):
        return -self.kp * (self.y - self.reference) - self.kd * self.v

    def do_step(self, current_time, step_size):
        return True
