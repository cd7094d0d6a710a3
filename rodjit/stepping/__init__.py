"""Time stepping: integrator steps, step-size control, event tracking, the compiled loop."""
