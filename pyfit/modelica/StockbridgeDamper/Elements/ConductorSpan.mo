within StockbridgeDamper.Elements;
model ConductorSpan "Laboratory conductor span: taut string between rigid ends, modal model (sine modes, every mode below 60 Hz for the default Drake ACSR span), a built-in shaker force at x_e, optionally the wind on one mode and a self-damping power law, and a damper clamp at x_d: clamp force in; clamp motion out"
  extends Interfaces.PartialBuiltInExcitation(exc_type=1, exc_amplitude(unit="N")=5, exc_f_start=10, exc_f_end=50);
  constant Integer N = 27 "Number of modes kept (27 x 2.18 Hz = 59 Hz for the default span)";
  parameter Real L(unit="m", min=0) = 30 "Span length";
  parameter Real T(unit="N", min=0) = 28000 "Conductor tension (about 20 % of the rated tensile strength of ACSR Drake, 140 kN)";
  parameter Real m_l(unit="kg/m", min=0) = 1.628 "Conductor mass per unit length (ACSR Drake)";
  parameter Real zeta(unit="1", min=0) = 0.002 "Modal damping ratio of every mode (conductor self-damping, linearised)";
  parameter Real x_d(unit="m", min=0) = 1.0 "Damper clamp position from the span end";
  parameter Real m_c(unit="kg", min=0) = 0.6 "Damper clamp mass, carried by the span at x_d (set the damper FMU's m_c to 0)";
  parameter Real x_e(unit="m", min=0) = 14.1 "Shaker force position from the span end";
  parameter Integer wind_mode(min=0, max=N) = 0 "Mode the wind drives (aeolian vibration at its frequency); 0 = no wind";
  parameter Real wind_D(unit="m", min=0) = 0.02814 "Conductor diameter for the wind power (ACSR Drake)";
  parameter Real wind_Iv(unit="1", min=0) = 0 "Turbulence intensity of the wind (0 = smooth flow)";
  parameter Real wind_Y_min(unit="m", min=0) = 1e-5 "Amplitude below which the wind's equivalent damping is held (the CIGRE power is finite at zero amplitude)";
  parameter Real sd_k(unit="1", min=0) = 0 "Self-damping power law P/L = sd_k*Y^sd_l*f^sd_m/(T/1000)^sd_n [W/m] (Y in m, f in Hz, T in N); 0 = none (zeta only)";
  parameter Real sd_l(unit="1") = 2.44 "Amplitude exponent of the self-damping law (Noiseux 1991)";
  parameter Real sd_m(unit="1") = 5.63 "Frequency exponent of the self-damping law (Noiseux 1991)";
  parameter Real sd_n(unit="1") = 2.76 "Tension exponent of the self-damping law (Noiseux 1991)";
  input Real F_clamp(unit="N", start=0) "Force the span applies to the damper clamp, upward (the damper FMU's F_clamp); the span feels -F_clamp";
  output Real y_d(unit="m") "Span displacement at the damper clamp";
  output Real v_d(unit="m/s") "Span velocity at the damper clamp";
  output Real a_d(unit="m/s2") "Span acceleration at the damper clamp";
  output Real y_e(unit="m") "Span displacement at the shaker";
  output Real E(unit="J") "Mechanical energy of the span (modal kinetic + potential) and the clamp's kinetic energy";
  output Real W_self(unit="J", nominal=1e-3) "Energy dissipated by the span's self-damping since t = 0";
  output Real W_shaker(unit="J", nominal=1e-3) "Work done by the shaker force since t = 0";
  output Real W_wind(unit="J", nominal=1e-3) "Work done by the wind since t = 0";
  Real q[N](each unit="m", each start=0, each nominal=1e-5) "Modal displacements (antinode amplitudes)";
  Real qd[N](each unit="m/s", each start=0, each nominal=1e-3) "Modal velocities";
  Real phi_d[N](each unit="1") "Mode shapes at the clamp";
  Real phi_e[N](each unit="1") "Mode shapes at the shaker";
  Real w[N](each unit="rad/s") "Natural circular frequencies";
  Real P_n[N](each unit="W") "Self-damping power per mode";
  Real E_n[N](each unit="J") "Energy per mode";
  Real A[N](each unit="m") "Modal amplitude envelope sqrt(q^2 + (qd/w)^2) (antinode amplitude of a steady vibration)";
  Real c_w[N](each unit="N.s/m") "Wind's equivalent negative damping per mode: 2*P_wind/(w^2*A^2), the CIGRE power (Foti & Martinelli 2018, eqs. 4-5)";
  Real c_s[N](each unit="N.s/m") "Self-damping law's equivalent damping per mode: 2*P_self/(w^2*A^2)";
  Real P_w[N](each unit="W") "Wind power into each mode";
  Real acc0[N](each unit="m/s2") "Modal accelerations without the clamp's inertia";
  Real pa[N](each unit="m/s2") "phi_d*acc0";
  Real p2[N](each unit="1") "phi_d^2";
  Real F_e(unit="N") "Shaker force";
  Real M(unit="kg") "Modal mass m_l*L/2";
  Real yd_n[N](each unit="m") "Modal contributions to y_d";
  Real vd_n[N](each unit="m/s") "Modal contributions to v_d";
  Real ye_n[N](each unit="m") "Modal contributions to y_e";
  Real ve_n[N](each unit="m/s") "Modal contributions to the velocity at the shaker";
equation
  M = m_l*L/2;
  F_e = excitation.y;
  for i in 1:N loop
    w[i] = i*3.14159265358979*sqrt(T/m_l)/L;
    phi_d[i] = sin(i*3.14159265358979*x_d/L);
    phi_e[i] = sin(i*3.14159265358979*x_e/L);
    // M*qdd + 2*zeta*w*M*qd + w^2*M*q = F_e*phi_e - (F_clamp + m_c*a_d)*phi_d, with a_d = sum(phi_d*qdd):
    // the clamp mass couples the modes; solved in closed form (Sherman-Morrison) so that no algebraic loop remains
    // a standing wave of antinode amplitude A stores the mean power c*w^2*A^2/2 in a force c*qd: the wind's and the
    // self-damping law's powers per span (L*f^3*D^4*fnc(A/D) and L*k*A^l*f^m/T^n) as amplitude-dependent damping
    A[i] = sqrt(q[i]^2 + (qd[i]/w[i])^2 + 1e-30); // 1e-30 m^2: a finite derivative at rest
    c_w[i] = if i == wind_mode then 2*L*(w[i]/(2*3.14159265358979))^3*wind_D^4
      *(-99.73*(max(A[i], wind_Y_min)/wind_D)^3 + 101.62*(max(A[i], wind_Y_min)/wind_D)^2 + 0.1627*max(A[i], wind_Y_min)/wind_D + 0.2256)
      /sqrt(1 + (wind_Iv/0.09)^2)/(w[i]^2*max(A[i], wind_Y_min)^2) else 0;
    c_s[i] = 2*L*sd_k*max(A[i], 1e-12)^(sd_l - 2)*(w[i]/(2*3.14159265358979))^sd_m/(T/1000)^sd_n/w[i]^2;
    P_w[i] = c_w[i]*qd[i]^2;
    acc0[i] = (F_e*phi_e[i] - F_clamp*phi_d[i] - 2*zeta*w[i]*M*qd[i] + (c_w[i] - c_s[i])*qd[i] - w[i]^2*M*q[i])/M;
    pa[i] = phi_d[i]*acc0[i];
    p2[i] = phi_d[i]^2;
    der(q[i]) = qd[i];
    der(qd[i]) = acc0[i] - m_c*a_d*phi_d[i]/M;
    P_n[i] = (2*zeta*w[i]*M + c_s[i])*qd[i]^2;
    E_n[i] = 0.5*M*(qd[i]^2 + w[i]^2*q[i]^2);
    yd_n[i] = phi_d[i]*q[i];
    vd_n[i] = phi_d[i]*qd[i];
    ye_n[i] = phi_e[i]*q[i];
    ve_n[i] = phi_e[i]*qd[i];
  end for;
  y_d = sum(yd_n);
  v_d = sum(vd_n);
  a_d = sum(pa)/(1 + m_c*sum(p2)/M);
  y_e = sum(ye_n);
  E = sum(E_n) + 0.5*m_c*v_d^2;
  der(W_self) = sum(P_n);
  der(W_shaker) = F_e*sum(ve_n);
  der(W_wind) = sum(P_w);
  annotation(experiment(StartTime=0, StopTime=10, Interval=1e-3, Tolerance=1e-8));
end ConductorSpan;
