"""The named columns of the engine's element tables, so that no slot is addressed by number.

A translational element is one row of ``el_int`` (kind, terminals) and one of ``el_real`` (its
numbers); a rotational element one row of ``rot_int`` and one of ``rot_real``. The laws of
:mod:`inerter.elements` read their parameters from the real row through these names. The joints'
tables (``jt_int``, ``jt_real``) and the point forces' are named here too, beside them.
"""

# -- el_int: a translational element's integers
KIND = 0                 # its code: its place in inerter.elements.KINDS
POINT_A = 1              # terminal a (point index)
POINT_B = 2              # terminal b (point index)
STATE = 3                # the offset of its internal states in z (y = [q, v, z]); 0 where it has none
STATES = 4               # how many internal states it has (an inerter device's series deflection and its
                         # rate, its dissipated energy: inerter.elements.device); 0 for most elements
ELEMENT_INT_COLUMNS = 5

# -- el_real: a translational element's numbers
COEFFICIENT = 0          # k (N/m), c (N.s/m) or b (kg)
FREE_LENGTH = 1          # a spring's free length L0 (m); 0 for the other kinds
CENTRIPETAL = 2          # an inerter: 1.0 with the centripetal term (Eq. 9), 0.0 without (Eq. 8)
MEET_LIMIT = 3           # the distance below which the terminals meet (m); 0: a pair checked earlier
# An inerter's device (inerter.elements.device; all 0.0 for an ideal inerter and the other kinds):
DEVICE = 4               # 1.0: the element declares a device (elements.NAME.device); its laws are skipped at 0.0
FLYWHEEL_RATIO = 5       # flywheel angle per unit of stroke, 2π/p or the gear ratio (rad/m); 0: no flywheel
FRICTION = 6             # 1.0: friction declared
COULOMB = 7              # Coulomb friction force F_c (N)
VISCOUS = 8              # viscous friction coefficient c_f (N.s/m)
VELOCITY_SCALE = 9       # the regularisation's velocity scale v_s (m/s); 1.0 where F_c is not declared
STOPS = 10               # 1.0: end stops declared
STOP_MIN = 11            # shortest terminal distance L_min (m); 0.0: no lower stop
STOP_MAX = 12            # longest terminal distance L_max (m); inf: no upper stop
STOP_STIFFNESS = 13      # contact stiffness k_s (N/m^n)
STOP_DAMPING = 14        # Hunt-Crossley contact damping c_s (N.s/m^(n+1))
STOP_EXPONENT = 15       # contact force exponent n (1: linear, 1.5: Hertz)
FLUID = 16               # 1.0: a helical-channel fluid inerter's channel damping declared
FLUID_LINEAR = 17        # its linear damping c_1 (N.s/m)
FLUID_QUADRATIC = 18     # its quadratic damping c_2 (N.s²/m²)
FIXED_DIRECTION = 19     # 1.0: the element acts along DIRECTION, its initial one (the small-displacement
                         # law of structural codes), not along the current r̂
DIRECTION = 20           # that direction, a unit vector in the global frame (3 columns; z = 0 in 2D); under
                         # SLIDER, the joint's axis in the frame of terminal a's body
SLIDER = 23              # 1.0: a prismatic joint's spring or damper: it acts along the joint's axis, fixed in
                         # terminal a's body (DIRECTION), and L is the signed slide ê·(r_b − r_a)
# An inerter device's masses and inertias (inerter.elements.device_inertia; all 0.0 where not declared):
INERTIA = 24             # 1.0: the device declares masses, a transverse inertia or a mount (its kinetic block)
HOUSING_MASS = 25        # housing mass m_h (kg), centre at HOUSING_CENTRE (m) from terminal a along r̂
HOUSING_CENTRE = 26
ROD_MASS = 27            # rod mass m_r (kg), centre at ROD_CENTRE (m) from terminal b along −r̂
ROD_CENTRE = 28
FLYWHEEL_MASS = 29       # flywheel mass m_f (kg), centre at FLYWHEEL_CENTRE (m) from terminal a along r̂
FLYWHEEL_CENTRE = 30
TRANSVERSE = 31          # transverse moment of inertia of housing, rod and flywheel together, about their centres (kg.m2)
MOUNT = 32               # 1.0: the housing's mount (a Hooke joint at terminal a) is declared: spin and gyroscopic terms
HOUSING_AXIAL = 33       # axial moment of inertia of housing and rod, which spin together (kg.m2)
FLYWHEEL_AXIAL = 34      # the flywheel's axial moment of inertia J (kg.m2), for its spin with the housing
MOUNT_AXIS = 35          # the Hooke joint's first axis a̅₁, a unit vector in terminal a's body frame (3 columns)
DEVICE_GRAVITY = 38      # the scene's gravity g (m/s², 3 columns; 0 without), for the weight of the device's masses
# An inerter device's internal states (inerter.elements.device; 0.0 where not declared):
SERIES = 41              # 1.0: a spring (and damper) in series with the inerter (device.compliance)
SERIES_STIFFNESS = 42    # its stiffness k_c (N/m)
SERIES_DAMPING = 43      # its damping c_c (N.s/m)
BACKLASH = 44            # 1.0: a gap in the series connection (device.backlash)
GAP = 45                 # the gap's total width (m): free play of ±GAP/2 about the engaged position
LOSS = 46                # 1.0: the dissipated energy integrated as a state (device.dissipated_energy)
# An inerter device's screw efficiency (inerter.elements.device; 0.0 where not declared):
EFFICIENCY = 47          # 1.0: an efficiency that depends on the power flow's direction (device.efficiency)
ETA_FORWARD = 48         # η_f: the part of the force that reaches the flywheel when the terminals drive it
ETA_BACKWARD = 49        # η_b: the part that reaches the terminals when the flywheel drives them
EFFICIENCY_MODE = 50     # the mode the last solve of Eq. (33) settled on: s = sign(L̈), +1.0 or −1.0 (kept where
                         # L̈ = 0); written by the engine (kernels.accelerations), +1.0 at the start
EFFICIENCY_SCALE = 51    # the switch's velocity scale v_s (m/s): b_eff smooth in tanh(L̇/v_s); 0.0: the exact switch
ELEMENT_REAL_COLUMNS = 52

# -- rot_int: a rotational element's integers
ROT_KIND = 0             # its code: its place in inerter.elements.KINDS
BODY_A = 1               # body a (2D: velocity index of its angle; 3D: body index; -1: ground)
BODY_B = 2
ROT_INT_COLUMNS = 3

# -- rot_real: a rotational element's numbers
FREE_ANGLE = 1           # a rotational spring's free angle φ0 (rad); COEFFICIENT is column 0 too
AXIS = 2                 # 3D: the axis n̄ in body a's frame, 3 columns
REL0 = 5                 # 3D: the initial relative orientation A_aᵀ A_b, 9 columns, row-major
PHI_REF = 14             # 3D: the element's wound angle at the last accepted step (rad; inerter.elements.winding),
                         # 0.0 at t = 0; written by the engine after each accepted step
ROT_REAL_COLUMNS_2D = 2
ROT_REAL_COLUMNS_3D = 15

# -- jt_int: a joint's integers (a 2D joint's row holds the first three columns)
JOINT_KIND = 0           # its kind's code: 2D kernels.REVOLUTE or PRISMATIC (a 2D screw too); 3D a label
                         # (compiled_spatial._JOINT_KIND) that the kernels do not read: the counts below say
                         # which rows the joint has. Its points a and b are in columns POINT_A and POINT_B, as
                         # in el_int (the kernels read both tables' terminals the same way, kernels._row_pair)
COINCIDENT = 3           # 3D: 1 where it has the three coincident rows r_b − r_a = 0
DOT1_ROWS = 4            # 3D: how many dot-1 rows s_a·s_b = 0 (≤ 3; their vectors from DOT1 of jt_real)
DOT2_ROWS = 5            # 3D: how many dot-2 rows s_a·(r_b − r_a) = 0 (≤ 2; their vectors from DOT2)
SCREW_ROW = 6            # 3D: 1 where the joint has the screw row (inerter.model.joints.Screw)
JOINT_INT_COLUMNS_2D = 3
JOINT_INT_COLUMNS_3D = 7

# -- jt_real of a 2D joint (inerter.model.joints.Prismatic2D; all 0.0 for a revolute joint)
PRISMATIC_NORMAL = 0     # n̄, the normal to the slide's axis t̄ in a's frame (t̄ turned by +90°; 2 columns)
PRISMATIC_PHI0 = 2       # φ0, the relative angle θ_b − θ_a the joint holds (rad; a 2D screw's at advance x₀)
PRISMATIC_RATIO = 3      # ρ = 2π/p of a 2D screw (rack and pinion): b's turn per unit of advance (rad/m); 0.0: none
PRISMATIC_ADVANCE0 = 4   # x₀, a 2D screw's initial advance t·(r_b − r_a) along t = A_a t̄ (m)
JOINT_REAL_COLUMNS_2D = 5

# -- jt_real of a 3D joint (the vectors of its rows, inerter.model.joints.SpatialJoint; unused columns 0.0)
DOT1 = 0                 # dot-1 row k's s̄_a in a's frame and s̄_b in b's frame at DOT1 + 6k (6 columns, k < 3)
DOT2 = 18                # dot-2 row k's s̄_a in a's frame at DOT2 + 3k (3 columns, k < 2)
SCREW = 24               # the screw's axis s̄ in a's frame (3 columns), read where SCREW_ROW of jt_int is 1
SCREW_REL0 = 27          # the initial relative orientation A_aᵀ A_b (9 columns, row-major)
SCREW_RATIO = 36         # ρ = 2π/p: the turn of b relative to a per unit of b's advance along the axis (rad/m)
SCREW_ADVANCE0 = 37      # the initial advance s·(r_b − r_a) (m)
JOINT_REAL_COLUMNS_3D = 38

# -- point forces (not element kinds, but tables of the same engine): fa_int, fa_real, pd_int,
#    pd_real, in_int; a force's real row starts with its direction's DIM components (2 or 3), and the
#    columns below count from there (``fa_real[f, dim + F_AMPLITUDE]``)
FORCE_POINT = 0          # fa_int, pd_int, in_int: the point the force acts at
FORCE_FUNCTION = 1       # fa_int: its time function (constant, sine, step)
F_VALUE, F_AMPLITUDE, F_FREQUENCY, F_PHASE, F_OFFSET, F_TIME, F_INITIAL = range(7)   # fa_real after d
PD_KP, PD_KD, PD_REFERENCE = range(3)                                                 # pd_real after d
