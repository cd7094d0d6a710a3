"""Rows of the per-run scratch array ``work`` (shape (WORK_ROWS, N+1)), shared by the steps."""
S = 0        # segment stresses
K = 1        # curvatures
VD = 2       # viscous sub-step: matrix diagonal
VCP = 3      #   Thomas factor
VINV = 4     #   1/pivots
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
WORK_ROWS = 15
