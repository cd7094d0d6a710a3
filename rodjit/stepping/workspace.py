"""Rows of the per-run scratch array ``work`` (shape (WORK_ROWS, N+1)), shared by the steps."""
S = 0        # segment stresses
K = 1        # curvatures
VD = 2       # viscous sub-step: matrix diagonal
VCP = 3      #   Thomas factor  } kept between calls: the factorisation of M + cK for
VINV = 4     #   1/pivots       } c = MEMO[0] (see viscous.factored); write them nowhere else
VRHS = 5     #   right-hand side
V0 = 6       #   copy of the incoming velocity
BA0 = 7      # beam sub-step: diagonals of M + c B
BA1 = 8
BA2 = 9
BL1 = 10     #   LDLᵀ factor
BL2 = 11
BDINV = 12
BY = 13      #   u + dt/4 v
BVK = 14     #   incoming velocity
MEMO = 15    # [0]: the c whose viscous factorisation VCP, VINV hold (0: none)
VF = 16      # the incoming velocity after the floor's damping sub-step
WORK_ROWS = 17
