

def test_the_closed_loop_slew_matches_the_exact_sampled_data_recursion(fmus):
    """reaction_wheel_slew with the PD law of rbcheck.slew closed from fmpy (u from q and
    w_body at every communication point, held over the step). From rest, I ω + h = 0, so the
    body turns about the eigenaxis n with ω̇ constant over each step: the recursion of
    rbcheck.slew.eigenaxis_reference is exact, and the FMU (rk8, 1e-10 1/s) meets it to its
    round-off: measured 6.7e-16 rad, asserted 1e-12 rad. L_world and the wheels-vs-body
    exchange: round-off of |h| ~ 2 N·m·s (measured 1e-15), asserted 1e-13. The final error
    1.79e-7 rad is the sampled-data PD loop's own (its decay over 40 s), not the FMU's."""
    from rbcheck.checks.wheels import slew

    s = slew(fmus["reaction_wheel_slew"], load_scene("reaction_wheel_slew"))
    print(s)
    assert s.phi0 == pytest.approx(math.pi / 2, rel=1e-15)
    assert s.body_momentum_max > 1.0 and s.wheel_rate_max > 50.0  # the wheels did take the momentum
    assert s.L_max < 1e-13 and s.exchange < 1e-13
    assert s.dphi < 1e-12 and s.dw < 1e-12
    assert s.final_error == pytest.approx(s.final_error_ref, abs=1e-12)
    assert s.final_error < 1e-6
