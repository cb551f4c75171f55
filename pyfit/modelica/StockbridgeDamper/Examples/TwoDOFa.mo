within StockbridgeDamper.Examples;
model TwoDOFa "Two-DOF system, configuration (a) Bouc-Wen between mass 2 and ground"
  extends TwoDOFBase;
equation
  connect(fixed.flange, boucWen.flange_a);
  connect(boucWen.flange_b, mass2.flange);
  annotation(experiment(StartTime=0, StopTime=120, Interval=1e-3, Tolerance=1e-8));
end TwoDOFa;
