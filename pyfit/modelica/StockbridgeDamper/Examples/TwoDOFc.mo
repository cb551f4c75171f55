within StockbridgeDamper.Examples;
model TwoDOFc "Two-DOF system, configuration (c) Bouc-Wen and cubic spring between mass 2 and ground"
  extends TwoDOFBase;
  parameter Real k_nl(unit="N/m3") = 1e6 "Cubic stiffness (the thesis's 1000 N/m3 is invisible at 10 N)";
  Components.CubicSpring cubicSpring(k3=k_nl) "Cubic spring";
equation
  connect(fixed.flange, boucWen.flange_a);
  connect(boucWen.flange_b, mass2.flange);
  connect(fixed.flange, cubicSpring.flange_a);
  connect(cubicSpring.flange_b, mass2.flange);
  annotation(experiment(StartTime=0, StopTime=120, Interval=1e-3, Tolerance=1e-8));
end TwoDOFc;
