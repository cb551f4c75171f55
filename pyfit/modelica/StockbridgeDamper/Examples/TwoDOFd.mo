within StockbridgeDamper.Examples;
model TwoDOFd "Two-DOF system, configuration (d) Bouc-Wen and cubic spring between mass 1 and mass 2"
  extends TwoDOFBase;
  parameter Real k_nl(unit="N/m3") = 1e6 "Cubic stiffness (the thesis's 1000 N/m3 is invisible at 10 N)";
  Components.CubicSpring cubicSpring(k3=k_nl) "Cubic spring";
equation
  connect(boucWen.flange_a, mass1.flange);
  connect(boucWen.flange_b, mass2.flange);
  connect(cubicSpring.flange_a, mass1.flange);
  connect(cubicSpring.flange_b, mass2.flange);
  annotation(experiment(StartTime=0, StopTime=120, Interval=1e-3, Tolerance=1e-8));
end TwoDOFd;
