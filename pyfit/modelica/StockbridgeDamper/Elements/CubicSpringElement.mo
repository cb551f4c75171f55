within StockbridgeDamper.Elements;
model CubicSpringElement "Cubic spring between ground and a driven point: relative motion s, v in; force on the driven point out (no state, direct feedthrough)"
  parameter Real k3(unit="N/m3") = 1e6 "Cubic stiffness coefficient (negative softens)";
  input Real s(unit="m", start=0) "Displacement of the driven point relative to the ground point";
  input Real v(unit="m/s", start=0) "Time derivative of s (not used by the force; part of the common element interface)";
  output Real f(unit="N") "Force the element applies to the driven point (= -k3*s^3)";
  Components.CubicSpring spring(k3=k3) "Cubic spring";
  Components.Fixed fixed "Ground point";
  Sources.Position position "Driven point";
equation
  position.s = s;
  connect(fixed.flange, spring.flange_a);
  connect(spring.flange_b, position.flange);
  f = -spring.f;
  annotation(__pyfit(inputDerivatives="s:v"), experiment(StartTime=0, StopTime=1, Interval=1e-4, Tolerance=1e-8));
end CubicSpringElement;
