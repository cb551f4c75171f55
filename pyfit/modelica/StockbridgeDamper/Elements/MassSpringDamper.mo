within StockbridgeDamper.Elements;
model MassSpringDamper "Mass on a linear spring and damper to ground, driven by a built-in force and an input force (e.g. from an element FMU): force in; motion out"
  extends Interfaces.PartialBuiltInExcitation(exc_type=2, exc_amplitude(unit="N")=120);
  parameter Real m(unit="kg", min=0) = 2 "Mass";
  parameter Real c(unit="N.s/m", min=0) = 10 "Viscous damping coefficient";
  parameter Real k(unit="N/m") = 5e4 "Linear stiffness";
  input Real f(unit="N", start=0) "Force on the mass from a connected element, positive in +y direction";
  output Real y(unit="m") "Displacement of the mass";
  output Real v(unit="m/s") "Velocity of the mass";
  output Real a(unit="m/s2") "Acceleration of the mass";
  Components.Mass mass(m=m) "Mass";
  Components.SpringDamper springDamper(k=k, c=c) "Linear spring and damper to ground";
  Components.Fixed fixed "Ground";
  Sources.Force force "Total force on the mass";
equation
  force.u = f + excitation.y;
  connect(force.flange, mass.flange);
  connect(springDamper.flange_b, mass.flange);
  connect(fixed.flange, springDamper.flange_a);
  y = mass.s;
  v = mass.v;
  a = der(mass.v);
  annotation(experiment(StartTime=0, StopTime=1, Interval=1e-4, Tolerance=1e-8));
end MassSpringDamper;
