package MyDampers "A user's own models beside the StockbridgeDamper library (stockbridge build --with examples/maxwell_candidate)"
  model MaxwellElement "Spring k_m in series with a dashpot of relaxation time tau: a stiffness and a loss factor that change with frequency (the loss peaks at 1/(2 pi tau))"
    extends StockbridgeDamper.Interfaces.PartialCompliant;
    parameter Real k_m(unit="N/m", min=0) = 0 "Stiffness of the series spring (0 switches the element off)";
    parameter Real tau(unit="s", min=0) = 0.005 "Relaxation time c_m/k_m of the series dashpot";
    Real s_d(unit="m", start=0, nominal=1e-3) "Elongation of the dashpot";
  equation
    der(s_d) = (s_rel - s_d)/tau;
    f = k_m*(s_rel - s_d);
  end MaxwellElement;

  model SDOFMaxwell "The SDOF oscillator of the library with a Maxwell element to ground (candidate effect maxwell_damping)"
    extends StockbridgeDamper.Examples.SDOFBoucWen;
    parameter Real k_m(unit="N/m", min=0) = 0 "Maxwell element: series stiffness (0 = absent)";
    parameter Real tau(unit="s", min=0) = 0.005 "Maxwell element: relaxation time";
    MaxwellElement maxwell(k_m=k_m, tau=tau) "Frequency-dependent stiffness and damping to ground";
  equation
    connect(maxwell.flange_b, mass.flange);
    connect(fixed.flange, maxwell.flange_a);
  end SDOFMaxwell;
end MyDampers;
