"""Truth models and validation: the simulator's secular truth, the nonlinear truth (both spacecraft integrated
numerically with heyoka: J2-J4 and drag), mean <-> osculating elements (Brouwer-Lyddane, first order), and the model
error of the secular ROE model against the nonlinear truth with the nonlinear Monte Carlo.
"""
